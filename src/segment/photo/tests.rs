//! The rounds of [`super::PhotoFit`] on synthetic scenes, with a segmenter that
//! answers from the truth (and one that errs), and the [`super::run`] driver.

use super::*;
use crate::app::{shapes, synth};
use crate::camera::Camera;
use crate::io::scene::SceneJson;

/// A mask of the image cut to `crop` (what a perfect segmenter returns).
fn in_crop(m: &Mask, crop: Crop) -> Mask {
    let mut out = Mask::empty(crop.side, crop.side);
    for y in 0..crop.side as i64 {
        for x in 0..crop.side as i64 {
            let (ix, iy) = (crop.x0 + x, crop.y0 + y);
            if ix >= 0 && iy >= 0 && ix < m.width as i64 && iy < m.height as i64 && m.get(ix as u32, iy as u32) {
                out.data[(y * crop.side as i64 + x) as usize] = 1;
            }
        }
    }
    out
}

/// Answers with the true silhouette; for view 0 it prefers a wrong reading (the
/// silhouette's left half removed) and offers the true one second.
struct Fake(Vec<Mask>);

impl Segmenter for Fake {
    fn segment(&mut self, jobs: &[SegmentJob], _: &[&Rgba]) -> Result<Vec<SegmentOutput>> {
        Ok(jobs
            .iter()
            .map(|j| {
                let full = in_crop(&self.0[j.view], j.crop);
                let mut out = SegmentOutput::single(full.clone(), vec![0.0; 16], 0.9);
                if j.view == 0 {
                    let b = PixelBox::of_mask(&full).unwrap();
                    let mut part = full;
                    let cut = (0.5 * (b.x0 + b.x1)) as u32;
                    for y in 0..part.height {
                        for x in 0..cut.min(part.width) {
                            part.data[(y * part.width + x) as usize] = 0;
                        }
                    }
                    out.candidates.insert(
                        0,
                        MaskCandidate {
                            mask: part,
                            logits: vec![0.0; 16],
                            score: 0.95,
                        },
                    );
                }
                out
            })
            .collect())
    }
}

fn scene() -> (Scene, Vec<Mask>) {
    scene_of(160, 0.7)
}

/// Three views of the toy plane, `side²` pixels, its bounding sphere spanning `fill`
/// of the half-side.
fn scene_of(side: u32, fill: f64) -> (Scene, Vec<Mask>) {
    let mesh = shapes::toy_plane();
    let s = synth::SynthSettings {
        views: 3,
        width: side,
        height: side,
        seed: 4,
        images: true,
        fill,
        ..Default::default()
    };
    let made = synth::synthesize(&mesh, &s, None).unwrap();
    let photos = (0..3)
        .map(|i| PhotoView {
            name: format!("view{i}"),
            camera: made.cameras[i],
            image: made.images[i].clone().into(),
            ignore: None,
            hint: PixelBox::of_mask(&made.masks[i]),
            index: i,
        })
        .collect();
    let json = SceneJson {
        version: 1,
        mesh: "toy.glb".into(),
        views: Vec::new(),
        initial_pose: None,
        ground_truth_pose: None,
        grasps: Vec::new(),
    };
    let scene = Scene {
        mesh,
        views: Vec::new(),
        photos,
        initial_pose: None,
        ground_truth_pose: Some(made.pose),
        grasps: Vec::new(),
        json,
        warnings: Vec::new(),
    };
    (scene, made.masks)
}

#[test]
fn the_fit_chooses_the_reading_that_agrees_with_the_geometry() {
    let (scene, truth) = scene();
    let mut fit = PhotoFit::new(scene, FitSettings::default(), PhotoSettings::default()).unwrap();
    let est = run(&mut fit, &mut Fake(truth.clone()), |_, _| {}).unwrap();
    let reports = fit.reports(Some(&est.pose()));
    // View 0: the segmenter's preference first, then the true reading, chosen by
    // the fitted silhouette; the other views had one reading each.
    assert_eq!(reports[0].picks.first(), Some(&0), "{:?}", reports[0].picks);
    assert_eq!(reports[0].picks.last(), Some(&1), "{:?}", reports[0].picks);
    assert!(fit.rounds() >= 2);
    for ((name, mask), t) in fit.segmenter_masks().iter().zip(&truth) {
        assert_eq!(metrics::hard_iou(mask.unwrap(), t), 1.0, "{name}");
    }
    // What is returned: the fitted silhouettes (the segmenter saw the whole object).
    let cameras: Vec<Camera> = fit
        .slots
        .iter()
        .map(|s| match s {
            Slot::Made(m) => m.photo.camera,
            Slot::Given(v) => *v.camera(),
        })
        .collect();
    for ((((name, mask), t), r), c) in fit.masks().iter().zip(&truth).zip(&reports).zip(&cameras) {
        let silhouette = hard::render(&fit.mesh, &est.pose(), c);
        assert_eq!(mask.unwrap(), &silhouette, "{name}");
        assert!(metrics::hard_iou(mask.unwrap(), t) > 0.97, "{name}");
        assert_eq!(r.returned, "fit");
    }
    let r = fit.result(&est, 0.0, None);
    assert_eq!(r.verdict, Some(Verdict::Ok));
    assert_eq!(r.masks.len(), 3);
}

#[test]
fn boxes_are_drawn_proposed_and_warmed_before_the_start() {
    let (mut scene, truth) = scene();
    for p in &mut scene.photos[1..] {
        p.hint = None;
    }
    let mut fit = PhotoFit::prepare(scene, FitSettings::default(), PhotoSettings::default()).unwrap();
    // One box: nothing proposed yet, and the start names the view it cannot place.
    let b = fit.boxes();
    assert!(b[0].given.is_some() && b[1].given.is_none() && b.iter().all(|v| v.proposed.is_none()));
    let e = fit.start().unwrap_err().to_string();
    assert!(e.contains("view 'view1'") && e.contains("at least two"), "{e}");
    assert_eq!(fit.warm_jobs().len(), 1);
    // A second box drawn: the third view's is proposed; a bad box is refused by name.
    let given = b[0].given.unwrap();
    let e = fit.set_box(1, Some([5.0, 5.0, 2.0, 9.0])).unwrap_err().to_string();
    assert!(e.contains("view 'view1'"), "{e}");
    let truth1 = PixelBox::of_mask(&truth[1]).unwrap().to_array();
    fit.set_box(1, Some(truth1)).unwrap();
    let b = fit.boxes();
    assert_eq!(b[0].given, Some(given));
    assert!(b[2].given.is_none() && b[2].proposed.is_some());
    // Points toggle: a second click near the first removes it.
    fit.toggle_point(0, 80.0, 80.0, true).unwrap();
    fit.toggle_point(0, 100.0, 60.0, false).unwrap();
    fit.toggle_point(0, 82.0, 81.0, true).unwrap();
    assert_eq!(fit.boxes()[0].points, vec![[100.0, 60.0, 0.0]]);
    assert!(fit.toggle_point(0, f64::NAN, 1.0, true).is_err() && fit.toggle_point(0, 1e6, 1.0, true).is_err());
    // The warm jobs are the start's own: the two boxed views' and the proposed box's.
    let warm = fit.warm_jobs();
    assert_eq!(warm.len(), 3);
    fit.start().unwrap();
    assert_eq!(fit.pending(), &warm[..]);
    assert_eq!(fit.pending()[0].points.len(), 1, "the point joins view 0's prompt");
    assert!(fit.warm_jobs().is_empty());
    assert!(fit.set_box(0, Some(given)).is_err(), "no boxes while a round runs");
}

#[test]
fn a_point_after_the_rounds_segments_that_view_again() {
    let (scene, truth) = scene();
    let mut fit = PhotoFit::new(scene, FitSettings::default(), PhotoSettings::default()).unwrap();
    let mut seg = Fake(truth);
    let est = run(&mut fit, &mut seg, |_, _| {}).unwrap();
    let rounds = fit.rounds();
    let areas = fit.reports(None)[2].areas.len();
    // A point off the object on view 2: that view alone is asked again, from the pose.
    let c = PixelBox::of_mask(fit.masks()[2].1.unwrap()).unwrap();
    fit.toggle_point(2, c.x0 - 3.0, c.y0 - 3.0, false).unwrap();
    assert!(!fit.is_done());
    let jobs = fit.pending().to_vec();
    assert_eq!(jobs.len(), 1);
    assert_eq!(jobs[0].view, 2);
    assert!(jobs[0].points.iter().any(|p| !p.object), "{:?}", jobs[0].points);
    let est2 = run(&mut fit, &mut seg, |_, _| {}).unwrap();
    assert!(fit.is_done() && fit.rounds() == rounds + 1);
    assert_eq!(fit.reports(None)[2].areas.len(), areas + 1);
    assert_eq!(
        fit.reports(None)[1].areas.len(),
        areas,
        "the other views were not asked"
    );
    assert!(metrics::pose_errors(fit_mesh(&fit), &est2.pose(), &est.pose()).add_rel < 0.01);
    // A box redrawn a little on view 1 once done: asked again on the crop it was last
    // segmented on (its encoding kept), prompted with the new box.
    let Slot::Made(m) = &fit.slots[1] else { unreachable!() };
    let last = m.crop;
    let c = PixelBox::of_mask(fit.masks()[1].1.unwrap()).unwrap();
    fit.set_box(1, Some([c.x0 + 1.0, c.y0 + 1.0, c.x1 - 1.0, c.y1 - 1.0]))
        .unwrap();
    let jobs = fit.pending().to_vec();
    assert_eq!((jobs.len(), jobs[0].view, jobs[0].crop), (1, 1, last));
    // Drawn far from it: a crop around the new box.
    run(&mut fit, &mut seg, |_, _| {}).unwrap();
    let w = c.x1 - c.x0;
    let x0 = if c.x0 > 80.0 { 1.0 } else { 159.0 - w };
    let far = PixelBox::new("view1", [x0, c.y0, x0 + w, c.y1], 160, 160).unwrap();
    fit.set_box(1, Some(far.to_array())).unwrap();
    assert_eq!(
        fit.pending()[0].crop,
        Crop::around(&far, PhotoSettings::default().crop_margin)
    );
}

/// `m` moved `by` pixels right (what leaves the image is lost).
fn moved_right(m: &Mask, by: u32) -> Mask {
    let mut out = Mask::empty(m.width, m.height);
    for y in 0..m.height {
        for x in by..m.width {
            out.data[(y * m.width + x) as usize] = m.data[(y * m.width + x - by) as usize];
        }
    }
    out
}

/// Answers with the true silhouette, but in the first round view 2's is moved 30
/// pixels right (a segmenter that took the wrong object).
struct Misplaced {
    truth: Vec<Mask>,
    calls: usize,
}

impl Segmenter for Misplaced {
    fn segment(&mut self, jobs: &[SegmentJob], _: &[&Rgba]) -> Result<Vec<SegmentOutput>> {
        self.calls += 1;
        Ok(jobs
            .iter()
            .map(|j| {
                let t = &self.truth[j.view];
                let m = if self.calls == 1 && j.view == 2 {
                    moved_right(t, 30)
                } else {
                    t.clone()
                };
                SegmentOutput::single(in_crop(&m, j.crop), vec![0.0; 16], 0.9)
            })
            .collect())
    }
}

#[test]
fn the_views_the_fit_doubts_are_segmented_again_first() {
    let (scene, truth) = scene();
    let mut fit = PhotoFit::new(scene, FitSettings::default(), PhotoSettings::default()).unwrap();
    let mut seg = Misplaced { truth, calls: 0 };
    // After each round's fit: its verdict's doubted views, the next round's jobs' order.
    let mut seen: Vec<(Vec<String>, Vec<usize>)> = Vec::new();
    run(&mut fit, &mut seg, |f, est| {
        if est.is_done() && !f.is_fitting() && !f.is_done() {
            let doubted = est.judgement().map(|j| j.doubted_views.clone()).unwrap_or_default();
            seen.push((doubted, f.pending().iter().map(|j| j.view).collect()));
        }
    })
    .unwrap();
    // Round 1's fit cannot explain view 2's mask (a failed verdict names no view; its
    // IoU and weight are the lowest): view 2 is asked first, the others after it.
    let (_, order) = seen.first().expect("a second round");
    assert_eq!(order.first(), Some(&2), "the misplaced view is asked first: {seen:?}");
    assert_eq!(order.len(), 3, "the others are asked too: {seen:?}");
}

fn fit_mesh(fit: &PhotoFit) -> &Mesh {
    &fit.mesh
}

#[test]
fn wrong_answers_are_errors_not_panics() {
    let (scene, truth) = scene();
    let mut fit = PhotoFit::new(scene, FitSettings::default(), PhotoSettings::default()).unwrap();
    assert_eq!(fit.pending().len(), 3);
    let e = fit.answer(Vec::new()).err().unwrap().to_string();
    assert!(e.contains("0 answers for 3"), "{e}");
    let mut answers = Fake(truth.clone()).segment(fit.pending(), &[]).unwrap();
    answers[1].candidates[0].mask = Mask::empty(3, 3);
    let e = fit.answer(answers.clone()).err().unwrap().to_string();
    assert!(e.contains("view1"), "{e}");
    // Nothing was taken: the same jobs wait, and a good answer is still accepted.
    assert_eq!(fit.pending().len(), 3);
    answers[1].candidates[0].mask = answers[0].candidates[0].mask.clone();
    answers[1].preferred = 7;
    let e = fit.answer(answers).err().unwrap().to_string();
    assert!(e.contains("view1") && e.contains("preferred"), "{e}");
    let good = Fake(truth).segment(fit.pending(), &[]).unwrap();
    let est = fit.answer(good).unwrap();
    assert!(fit.is_fitting() && fit.pending().is_empty());
    let e = fit.advance(&est).unwrap_err().to_string();
    assert!(e.contains("once it is done"), "{e}");
}

#[test]
fn made_masks_are_fitted_with_capped_contour_distances_and_a_bad_cap_is_refused() {
    let (scene, truth) = scene();
    let mut fit = PhotoFit::new(scene.clone(), FitSettings::default(), PhotoSettings::default()).unwrap();
    let jobs = fit.pending().to_vec();
    let est = fit.answer(Fake(truth.clone()).segment(&jobs, &[]).unwrap()).unwrap();
    assert_eq!(est.views().len(), 3);
    assert!(est.views().iter().all(|v| v.contour_cap() == Some(0.15)));
    // And refined by their photographs' colours (the region term).
    assert!(est.views().iter().all(|v| v.colour_refined()));
    // Uncapped when asked.
    let plain = PhotoSettings {
        contour_cap: None,
        ..PhotoSettings::default()
    };
    let mut fit = PhotoFit::new(scene.clone(), FitSettings::default(), plain).unwrap();
    let jobs = fit.pending().to_vec();
    let est = fit.answer(Fake(truth).segment(&jobs, &[]).unwrap()).unwrap();
    assert!(est
        .views()
        .iter()
        .all(|v| v.contour_cap().is_none() && v.colour_refined()));
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let s = PhotoSettings {
            contour_cap: Some(bad),
            ..PhotoSettings::default()
        };
        let e = PhotoFit::prepare(scene.clone(), FitSettings::default(), s)
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("out of range"), "{bad}: {e}");
    }
}

/// Answers with the true silhouette, except view 2's: moved 30 pixels right, then 24,
/// then 30 … (a segmenter that keeps taking the wrong object; the masks never settle,
/// and no fit is `ok`).
struct Wandering {
    truth: Vec<Mask>,
    calls: usize,
}

impl Segmenter for Wandering {
    fn segment(&mut self, jobs: &[SegmentJob], _: &[&Rgba]) -> Result<Vec<SegmentOutput>> {
        self.calls += 1;
        let by = if self.calls % 2 == 1 { 30 } else { 24 };
        Ok(jobs
            .iter()
            .map(|j| {
                let t = &self.truth[j.view];
                let m = if j.view == 2 { moved_right(t, by) } else { t.clone() };
                SegmentOutput::single(in_crop(&m, j.crop), vec![0.0; 16], 0.9)
            })
            .collect())
    }
}

#[test]
fn fits_in_doubt_search_afresh_only_as_often_as_asked() {
    for (searches, expected) in [(2, [true, true, false]), (3, [true, true, true])] {
        let (scene, truth) = scene();
        let settings = PhotoSettings {
            searches,
            ..PhotoSettings::default()
        };
        let mut fit = PhotoFit::new(scene, FitSettings::default(), settings).unwrap();
        let mut seg = Wandering { truth, calls: 0 };
        // Each finished fit: whether it searched the orientations, and its verdict.
        let mut fits: Vec<(bool, Option<Verdict>)> = Vec::new();
        run(&mut fit, &mut seg, |_, est| {
            if est.is_done() {
                fits.push((est.progress().search_total > 0, est.judgement().map(|j| j.verdict)));
            }
        })
        .unwrap();
        assert_eq!(fits.len(), 3, "searches {searches}: {fits:?}");
        assert!(
            fits.iter().all(|(_, v)| *v != Some(Verdict::Ok)),
            "every fit in doubt: {fits:?}"
        );
        assert_eq!(
            fits.iter().map(|f| f.0).collect::<Vec<_>>(),
            expected,
            "searches {searches}"
        );
        // A point added after the rounds: the refit of a fit in doubt searches again.
        let c = PixelBox::of_mask(fit.masks()[2].1.unwrap()).unwrap();
        fit.toggle_point(2, c.x1 + 3.0, c.y1 + 3.0, false).unwrap();
        let est = run(&mut fit, &mut seg, |_, _| {}).unwrap();
        assert!(
            est.progress().search_total > 0,
            "searches {searches}: the refit searched"
        );
    }
}

/// Answers every job with its prompt's box filled: what SAM does with a box around
/// a whole photograph (it takes in the table and the wall).
struct Boxy;

impl Segmenter for Boxy {
    fn segment(&mut self, jobs: &[SegmentJob], _: &[&Rgba]) -> Result<Vec<SegmentOutput>> {
        Ok(jobs
            .iter()
            .map(|j| {
                let side = j.crop.side;
                let mut m = Mask::empty(side, side);
                let [x0, y0, x1, y1] = j.prompt_box.map(|v| v.round().clamp(0.0, side as f64) as u32);
                for y in y0..y1 {
                    for x in x0..x1 {
                        m.data[(y * side + x) as usize] = 1;
                    }
                }
                SegmentOutput::single(m, vec![0.0; 16], 0.9)
            })
            .collect())
    }
}

#[test]
fn a_box_around_the_whole_photograph_is_replaced_by_the_geometrys() {
    // The object small in its photographs, and view 0's box around all of it.
    let side = 320.0;
    let (mut scene, truth) = scene_of(side as u32, 0.25);
    scene.photos[0].hint = Some(PixelBox::new("view0", [0.0, 0.0, side, side], 320, 320).unwrap());
    let tight: Vec<PixelBox> = truth.iter().map(|m| PixelBox::of_mask(m).unwrap()).collect();
    let mut fit = PhotoFit::prepare(scene.clone(), FitSettings::default(), PhotoSettings::default()).unwrap();
    let loose = fit.loose_boxes();
    let (within, ratio) = loose[0].expect("the whole photograph's box is too loose");
    assert!(
        ratio > boxes::LOOSE_BOX && loose[1].is_none() && loose[2].is_none(),
        "{loose:?}"
    );
    // The geometry's box holds the object (loosely), within the drawn one.
    assert!(
        within.x0 <= tight[0].x0 && within.y0 <= tight[0].y0 && within.x1 >= tight[0].x1 && within.y1 >= tight[0].y1
    );
    assert!(within.size().max_element() < 0.5 * side, "{within:?}");
    let warm = fit.warm_jobs();
    fit.start().unwrap();
    assert_eq!(fit.pending(), &warm[..], "the warmed jobs are the start's");
    assert!(fit.warnings()[0].contains("view 'view0'") && fit.warnings()[0].contains("the box drawn is"));
    // With a segmenter that fills its box, the whole photograph's box would have given
    // a mask of the whole photograph; the geometry's gives one near the object, and the
    // view sits out the first fit.
    let est = run(&mut fit, &mut Boxy, |p, e| {
        if p.rounds() == 1 && !e.is_done() {
            assert_eq!(e.views().len(), 2, "view 0 sits out the first fit");
        }
    })
    .unwrap();
    let r = fit.result(&est, 0.0, None);
    assert_eq!(r.masks[0].first_box_from, "geometry");
    assert!(
        (r.masks[0].areas[0] as f64) < 0.1 * side * side,
        "{:?}",
        r.masks[0].areas
    );
    // Boxes as drawn normally are left alone.
    let (mut scene, _) = scene_of(side as u32, 0.25);
    let fit = PhotoFit::prepare(scene.clone(), FitSettings::default(), PhotoSettings::default()).unwrap();
    assert!(fit.loose_boxes().iter().all(Option::is_none));
    // Every box around its whole photograph: nothing to correct them by; the masks of
    // the whole photographs are fitted, each view warned of, and the fit is not `ok`.
    for p in &mut scene.photos {
        p.hint = Some(PixelBox::new(&p.name, [0.0, 0.0, side, side], 320, 320).unwrap());
    }
    let mut fit = PhotoFit::new(scene, FitSettings::default(), PhotoSettings::default()).unwrap();
    assert!(fit.loose_boxes().iter().all(Option::is_none));
    let est = run(&mut fit, &mut Boxy, |_, _| {}).unwrap();
    for i in 0..3 {
        let named = fit
            .warnings()
            .iter()
            .filter(|w| w.starts_with(&format!("view 'view{i}': the segmenter's mask covers")));
        assert_eq!(named.count(), 1, "{:?}", fit.warnings());
    }
    assert_ne!(fit.result(&est, 0.0, None).verdict, Some(Verdict::Ok));
}

#[test]
fn a_re_prompt_stays_within_the_drawn_box() {
    let mut m = Mask::empty(40, 40);
    m.data.iter_mut().for_each(|v| *v = 1);
    let b = PixelBox::new("v", [10.0, 10.0, 20.0, 20.0], 40, 40).unwrap();
    keep_within(&mut m, &b);
    // 30 % of the side and 2 px each way: columns and rows 5..25.
    assert_eq!(BOX_SLACK, 0.3);
    assert_eq!(m.area(), 20 * 20);
    assert!(m.get(5, 5) && m.get(24, 24) && !m.get(4, 10) && !m.get(25, 10) && !m.get(10, 25));
    // A fitted pose far off: the re-prompt's box is the drawn one, not the pose's.
    let (scene, truth) = scene();
    let mut fit = PhotoFit::new(scene, FitSettings::default(), PhotoSettings::default()).unwrap();
    let est = run(&mut fit, &mut Fake(truth.clone()), |_, _| {}).unwrap();
    let mut away = est.pose();
    let Slot::Made(made) = &mut fit.slots[1] else {
        panic!("made")
    };
    let cam = made.photo.camera;
    // Move the object sideways in view 1 by its box's longer side.
    let drawn = made.photo.hint.unwrap();
    let depth = cam.to_camera(away.translation).z;
    let shift = (drawn.x1 - drawn.x0).max(drawn.y1 - drawn.y0) * depth / cam.fx;
    away.translation += cam.rotation.transpose() * glam::DVec3::new(shift, 0.0, 0.0);
    let job = reprompt(&fit.mesh, &away, 1, made, 0.15);
    let [x0, y0, x1, y1] = job.prompt_box;
    let (cx0, cy0) = (job.crop.x0 as f64, job.crop.y0 as f64);
    let slack = BOX_SLACK * (drawn.x1 - drawn.x0).max(drawn.y1 - drawn.y0) + 2.0;
    assert!(
        cx0 + x0 >= drawn.x0 - slack - 2.0 && cx0 + x1 <= drawn.x1 + slack + 2.0,
        "{:?} in crop {:?}, drawn {drawn:?}",
        job.prompt_box,
        job.crop
    );
    assert!(cy0 + y0 >= drawn.y0 - slack - 2.0 && cy0 + y1 <= drawn.y1 + slack + 2.0);
}
