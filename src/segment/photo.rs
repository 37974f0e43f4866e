//! [`PhotoFit`]: photographs in, pose out. The masks a scene lacks are made by a
//! prompted segmenter and corrected by the fit itself, round by round:
//!
//! 0. every view without a mask gets a box (the user's, or the geometry's:
//!    [`super::hints`]) and a [`SegmentJob`] prompted with it;
//! 1. the masks the segmenter returns and the given ones are fitted
//!    ([`Estimator`], from no initial pose);
//! 2. each made mask is asked for again from the fitted pose ([`prompt::from_pose`]):
//!    the silhouette's tight box, a point on the object, a point against the previous
//!    mask's excess, the previous mask as mask input — the views the fit doubts first —
//!    and the masks are refitted (from the previous pose when its verdict was `ok`);
//! 3. until every made mask changed by less than [`PhotoSettings::converged_iou`], or
//!    after [`PhotoSettings::rounds`] re-prompts.
//!
//! Like [`Estimator`], it is step-wise and does no inference itself: it names the
//! segmentations it needs ([`PhotoFit::pending`]) and takes the answers
//! ([`PhotoFit::answer`]) — from a segmenter in this thread, a pool of threads or the
//! browser's Workers alike. [`run`] drives it with a [`Segmenter`].

use super::hints::{box_of_sphere, sphere_from_boxes};
use super::prompt::{self, Crop, MaskCandidate, SegmentJob, SegmentOutput};
use crate::error::{Error, Result};
use crate::estimator::{Estimator, FitResult, FitSettings, MaskReport};
use crate::io::scene::Scene;
use crate::mask::Mask;
use crate::mesh::Mesh;
use crate::metrics;
use crate::pose::Pose;
use crate::raster::hard;
use crate::verdict::Verdict;
use crate::view::{PhotoView, PixelBox, Rgba, View, ViewSources};
use serde::{Deserialize, Serialize};

/// How masks are made and corrected.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PhotoSettings {
    /// Re-prompts from the fitted pose after the first fit (default 2).
    pub rounds: usize,
    /// The segmenter's square around a box: `1 + 2·margin` times its longest side
    /// (default 0.5).
    pub crop_margin: f64,
    /// Masks that all changed less than this (IoU with the previous round's) end the
    /// rounds (default 0.98).
    pub converged_iou: f64,
}

impl Default for PhotoSettings {
    fn default() -> Self {
        PhotoSettings {
            rounds: 2,
            crop_margin: 0.5,
            converged_iou: 0.98,
        }
    }
}

/// What makes masks: answers [`SegmentJob`]s on the views' photographs, in order.
pub trait Segmenter {
    /// One output per job, in order; `images[i]` is job i's view's photograph.
    fn segment(&mut self, jobs: &[SegmentJob], images: &[&Rgba]) -> Result<Vec<SegmentOutput>>;
}

/// A view of the fit: given with its mask, or made from a photograph.
#[derive(Debug, Clone)]
// A handful per scene, moved never: the size difference costs nothing.
#[allow(clippy::large_enum_variant)]
enum Slot {
    Given(View),
    Made(Made),
}

#[derive(Debug, Clone)]
struct Made {
    photo: PhotoView,
    crop: Crop,
    /// The latest mask (full image) and its logits, once made.
    mask: Option<(Mask, Vec<f32>)>,
    /// The fitted pose's silhouette the pending job was prompted from (the segmenter's
    /// masks are chosen by it).
    reference: Option<Mask>,
    report: MaskReport,
}

enum Stage {
    /// Waiting for the segmenter's answers to `pending`.
    Segment,
    /// Fitting round `round`'s masks.
    Fit(Box<Estimator>),
    /// Finished: the last fit.
    Done(Box<Estimator>),
}

/// Photographs in, pose out (module doc).
pub struct PhotoFit {
    mesh: Mesh,
    settings: FitSettings,
    photo: PhotoSettings,
    initial_pose: Option<Pose>,
    slots: Vec<Slot>,
    pending: Vec<SegmentJob>,
    stage: Stage,
    /// Rounds of segmentation answered so far.
    round: usize,
    /// The scene indices of the views in the current fit (a made mask that came back
    /// empty sits a round out).
    fitted: Vec<usize>,
    converged: bool,
    warnings: Vec<String>,
}

impl PhotoFit {
    /// Starts on `scene`: boxes for every view without a mask, and the first jobs.
    ///
    /// Errors: a scene without photographs to segment, boxes from the geometry that
    /// cannot be placed (named by view), invalid settings.
    pub fn new(scene: Scene, settings: FitSettings, photo: PhotoSettings) -> Result<PhotoFit> {
        settings.validate()?;
        if scene.photos.is_empty() {
            return Err(Error::Settings(
                "photographs: every view has a mask; nothing to segment".into(),
            ));
        }
        if !(photo.crop_margin >= 0.0
            && photo.crop_margin <= 4.0
            && photo.converged_iou > 0.0
            && photo.converged_iou <= 1.0)
        {
            return Err(Error::Settings(format!(
                "photographs: settings out of range: {photo:?}"
            )));
        }
        let n = scene.views.len() + scene.photos.len();
        let mut given = scene.views.into_iter();
        let mut photos = scene.photos.into_iter().peekable();
        let mut slots = Vec::with_capacity(n);
        for i in 0..n {
            if photos.peek().is_some_and(|p| p.index == i) {
                let p = photos.next().expect("peeked");
                let first_box = p.hint.map(|b| b.to_array()).unwrap_or_default();
                slots.push(Slot::Made(Made {
                    crop: Crop { x0: 0, y0: 0, side: 0 },
                    mask: None,
                    reference: None,
                    report: MaskReport {
                        view: p.name.clone(),
                        first_box_from: if p.hint.is_some() { "box" } else { "geometry" }.into(),
                        first_box,
                        areas: Vec::new(),
                        changes: Vec::new(),
                        picks: Vec::new(),
                        score: 0.0,
                        iou_with_fit: 0.0,
                    },
                    photo: p,
                }));
            } else {
                let v = given
                    .next()
                    .ok_or_else(|| Error::Settings("photographs: the scene's view indices do not add up".into()))?;
                slots.push(Slot::Given(v));
            }
        }
        let mut fit = PhotoFit {
            mesh: scene.mesh,
            settings,
            photo,
            initial_pose: scene.initial_pose,
            slots,
            pending: Vec::new(),
            stage: Stage::Segment,
            round: 0,
            fitted: Vec::new(),
            converged: false,
            warnings: Vec::new(),
        };
        fit.first_jobs()?;
        Ok(fit)
    }

    /// Boxes for the views without one, from the others' boxes and masks, then a job
    /// per made view.
    fn first_jobs(&mut self) -> Result<()> {
        let hinted: Vec<(&crate::camera::Camera, PixelBox, &str)> = self
            .slots
            .iter()
            .filter_map(|s| match s {
                Slot::Given(v) => PixelBox::of_mask(v.mask()).map(|b| (v.camera(), b, v.name())),
                Slot::Made(m) => m.photo.hint.map(|b| (&m.photo.camera, b, m.photo.name.as_str())),
            })
            .collect();
        let sphere = if self
            .slots
            .iter()
            .any(|s| matches!(s, Slot::Made(m) if m.photo.hint.is_none()))
        {
            Some(sphere_from_boxes(&hinted)?)
        } else {
            None
        };
        let margin = self.photo.crop_margin;
        for (i, s) in self.slots.iter_mut().enumerate() {
            let Slot::Made(m) = s else { continue };
            let b = match (m.photo.hint, sphere) {
                (Some(b), _) => b,
                (None, Some((c, r))) => box_of_sphere(&m.photo.name, &m.photo.camera, c, r)?,
                (None, None) => unreachable!("a sphere is made when a view has no box"),
            };
            m.report.first_box = b.to_array();
            m.crop = Crop::around(&b, margin);
            self.pending.push(SegmentJob::from_box(i, m.crop, &b));
        }
        Ok(())
    }

    /// The segmentations the fit waits for (empty while it fits or when done).
    pub fn pending(&self) -> &[SegmentJob] {
        match self.stage {
            Stage::Segment => &self.pending,
            _ => &[],
        }
    }

    /// The photograph of scene view `view` (for a segmenter), if it is a made one.
    pub fn image(&self, view: usize) -> Option<&Rgba> {
        match self.slots.get(view) {
            Some(Slot::Made(m)) => Some(&m.photo.image),
            _ => None,
        }
    }

    /// Takes the answers to [`PhotoFit::pending`], in order, and starts the round's fit.
    ///
    /// Errors: not waiting for answers, the wrong number of them, a mask of the wrong
    /// size, or no view left to fit.
    pub fn answer(&mut self, outputs: Vec<SegmentOutput>) -> Result<()> {
        if !matches!(self.stage, Stage::Segment) || outputs.len() != self.pending.len() {
            return Err(Error::Settings(format!(
                "photographs: {} answers for {} segmentations asked",
                outputs.len(),
                self.pending().len()
            )));
        }
        // Every answer is checked before any is taken: a wrong one changes nothing.
        for (job, out) in self.pending.iter().zip(&outputs) {
            let Some(Slot::Made(m)) = self.slots.get(job.view) else {
                return Err(Error::Settings(format!(
                    "photographs: view {} is not one to segment",
                    job.view
                )));
            };
            let side = job.crop.side;
            let sized = |c: &MaskCandidate| {
                (c.mask.width, c.mask.height) == (side, side) && c.mask.data.len() == (side * side) as usize
            };
            if out.candidates.is_empty() || out.preferred >= out.candidates.len() || !out.candidates.iter().all(sized) {
                return Err(Error::View {
                    view: m.photo.name.clone(),
                    problem: format!(
                        "the segmenter's answer is not {side}×{side} masks with a preferred one among them"
                    ),
                });
            }
        }
        let mut all_converged = self.round > 0;
        for (job, out) in std::mem::take(&mut self.pending).into_iter().zip(outputs) {
            let Some(Slot::Made(m)) = self.slots.get_mut(job.view) else {
                unreachable!("checked above");
            };
            let (w, h) = (m.photo.camera.width, m.photo.camera.height);
            let mut masks: Vec<(Mask, MaskCandidate)> = out
                .candidates
                .into_iter()
                .map(|c| (job.crop.to_image(&c.mask, w, h), c))
                .collect();
            // The segmenter's choice, or — once there is a fit — the reading that
            // agrees best with the fitted silhouette.
            let pick = match m.reference.take() {
                Some(r) => (0..masks.len())
                    .max_by(|&a, &b| metrics::hard_iou(&masks[a].0, &r).total_cmp(&metrics::hard_iou(&masks[b].0, &r)))
                    .expect("candidates checked non-empty"),
                None => out.preferred,
            };
            m.report.picks.push(pick);
            let (mask, chosen) = masks.swap_remove(pick);
            if let Some((prev, _)) = &m.mask {
                let change = metrics::hard_iou(prev, &mask);
                all_converged &= change >= self.photo.converged_iou;
                m.report.changes.push(change);
            }
            m.report.areas.push(mask.area());
            m.report.score = chosen.score;
            m.crop = job.crop;
            m.mask = Some((mask, chosen.logits));
        }
        self.round += 1;
        self.converged = all_converged;
        self.start_fit()
    }

    /// The views of this round's fit: the given ones and every made mask with an object
    /// pixel the ignore mask leaves.
    fn start_fit(&mut self) -> Result<()> {
        let mut views = Vec::with_capacity(self.slots.len());
        self.fitted.clear();
        for (i, s) in self.slots.iter().enumerate() {
            let v = match s {
                Slot::Given(v) => v.clone(),
                Slot::Made(m) => {
                    let (mask, _) = m.mask.as_ref().expect("answered before a fit");
                    let p = &m.photo;
                    let sources = ViewSources::files("(made by the segmenter)", "ignore mask", "photograph");
                    match View::new(
                        &p.name,
                        p.camera,
                        mask.clone(),
                        p.ignore.clone(),
                        Some(p.image.clone()),
                        &sources,
                    ) {
                        Ok(v) => v,
                        Err(Error::EmptyMask { .. }) => {
                            self.warnings.push(format!(
                                "view '{}': the segmenter found no object in round {}: the view sits this fit out",
                                p.name, self.round
                            ));
                            continue;
                        }
                        Err(e) => return Err(e),
                    }
                }
            };
            views.push(v);
            self.fitted.push(i);
        }
        if views.is_empty() {
            return Err(Error::Settings(
                "photographs: the segmenter found the object in no view: check the boxes".into(),
            ));
        }
        let est = Estimator::new(self.mesh.clone(), views, self.initial_pose, self.settings.clone())?;
        self.stage = Stage::Fit(Box::new(est));
        Ok(())
    }

    /// The round's estimator while it fits (step it until done, then [`PhotoFit::advance`]).
    pub fn estimator_mut(&mut self) -> Option<&mut Estimator> {
        match &mut self.stage {
            Stage::Fit(e) => Some(e),
            _ => None,
        }
    }

    /// The estimator of the current or the last fit.
    pub fn estimator(&self) -> Option<&Estimator> {
        match &self.stage {
            Stage::Fit(e) | Stage::Done(e) => Some(e),
            Stage::Segment => None,
        }
    }

    /// After a round's fit is done: re-prompts from its pose (module doc), or ends.
    ///
    /// Errors: the round's fit is not done.
    pub fn advance(&mut self) -> Result<()> {
        let est = match std::mem::replace(&mut self.stage, Stage::Segment) {
            Stage::Fit(e) if e.is_done() => e,
            other => {
                self.stage = other;
                return Err(Error::Settings(
                    "photographs: advance before the round's fit is done".into(),
                ));
            }
        };
        if self.converged || self.round > self.photo.rounds {
            self.stage = Stage::Done(est);
            return Ok(());
        }
        let pose = est.pose();
        let judgement = est.judgement().cloned();
        let ok = judgement.as_ref().is_some_and(|j| j.verdict == Verdict::Ok);
        // From the previous pose when it was good (no search), else searched afresh.
        self.initial_pose = ok.then_some(pose);
        let doubted: Vec<String> = judgement.map(|j| j.doubted_views).unwrap_or_default();
        let margin = self.photo.crop_margin;
        let mut jobs = Vec::new();
        for (i, s) in self.slots.iter_mut().enumerate() {
            let Slot::Made(m) = s else { continue };
            let silhouette = hard::render(&self.mesh, &pose, &m.photo.camera);
            let tight = PixelBox::of_mask(&silhouette);
            // A new square when the silhouette left the old one or shrank within it (the
            // previous logits are then of another crop).
            let keep = tight.is_some_and(|b| m.crop.holds(&b, 0.05, 0.25));
            if !keep {
                if let Some(b) = tight {
                    m.crop = Crop::around(&b, margin);
                }
            }
            let previous = m
                .mask
                .as_ref()
                .filter(|_| keep)
                .map(|(mask, logits)| (mask, logits.as_slice()));
            let job = prompt::from_pose(i, m.crop, &silhouette, previous).unwrap_or_else(|| {
                // The pose puts the object outside this photograph: ask with the first box.
                let b = PixelBox::new(
                    &m.photo.name,
                    m.report.first_box,
                    m.photo.camera.width,
                    m.photo.camera.height,
                )
                .expect("validated when first made");
                m.crop = Crop::around(&b, margin);
                SegmentJob::from_box(i, m.crop, &b)
            });
            m.reference = tight.is_some().then_some(silhouette);
            jobs.push((doubted.contains(&m.photo.name), job));
        }
        // The views the fit doubts first.
        jobs.sort_by_key(|(doubted, _)| !doubted);
        self.pending = jobs.into_iter().map(|(_, j)| j).collect();
        Ok(())
    }

    /// Whether the rounds are over.
    pub fn is_done(&self) -> bool {
        matches!(self.stage, Stage::Done(_))
    }

    /// Segmentation rounds answered so far.
    pub fn rounds(&self) -> usize {
        self.round
    }

    /// Each scene view's mask as it stands (given or made; `None` before it is made),
    /// with the view's name, in scene order.
    pub fn masks(&self) -> Vec<(&str, Option<&Mask>)> {
        self.slots
            .iter()
            .map(|s| match s {
                Slot::Given(v) => (v.name(), Some(v.mask())),
                Slot::Made(m) => (m.photo.name.as_str(), m.mask.as_ref().map(|(k, _)| k)),
            })
            .collect()
    }

    /// How each made mask came about (with its IoU against the current fit's
    /// silhouette, once there is a fit).
    pub fn reports(&self) -> Vec<MaskReport> {
        let pose = self.estimator().map(|e| e.pose());
        self.slots
            .iter()
            .filter_map(|s| match s {
                Slot::Made(m) => {
                    let mut r = m.report.clone();
                    if let (Some(p), Some((mask, _))) = (pose, &m.mask) {
                        r.iou_with_fit = metrics::hard_iou(mask, &hard::render(&self.mesh, &p, &m.photo.camera));
                    }
                    Some(r)
                }
                Slot::Given(_) => None,
            })
            .collect()
    }

    /// The result of the last fit, with the made masks' reports (SPEC §3); `None`
    /// before the first fit.
    pub fn result(&self, seconds: f64, ground_truth: Option<&Pose>) -> Option<FitResult> {
        let mut r = self.estimator()?.result(seconds, ground_truth);
        r.masks = self.reports();
        Some(r)
    }

    /// What was accepted with a reservation (a view that sat a round out).
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }
}

/// Drives `fit` to the end with `segmenter`, calling `progress` after every
/// segmentation round and every fit.
///
/// Errors: the segmenter's, the fit's.
pub fn run(fit: &mut PhotoFit, segmenter: &mut dyn Segmenter, mut progress: impl FnMut(&PhotoFit)) -> Result<()> {
    while !fit.is_done() {
        if let Some(est) = fit.estimator_mut() {
            est.run(usize::MAX)?;
            fit.advance()?;
        } else {
            let jobs = fit.pending().to_vec();
            let images: Vec<&Rgba> = jobs
                .iter()
                .map(|j| fit.image(j.view).expect("jobs are for made views"))
                .collect();
            let outputs = segmenter.segment(&jobs, &images)?;
            fit.answer(outputs)?;
        }
        progress(fit);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::app::{shapes, synth};
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
        let mesh = shapes::toy_plane();
        let s = synth::SynthSettings {
            views: 3,
            width: 160,
            height: 160,
            seed: 4,
            images: true,
            ..Default::default()
        };
        let made = synth::synthesize(&mesh, &s, None).unwrap();
        let photos = (0..3)
            .map(|i| PhotoView {
                name: format!("view{i}"),
                camera: made.cameras[i],
                image: made.images[i].clone(),
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
        run(&mut fit, &mut Fake(truth.clone()), |_| {}).unwrap();
        let reports = fit.reports();
        // View 0: the segmenter's preference first, then the true reading, chosen by
        // the fitted silhouette; the other views had one reading each.
        assert_eq!(reports[0].picks.first(), Some(&0), "{:?}", reports[0].picks);
        assert_eq!(reports[0].picks.last(), Some(&1), "{:?}", reports[0].picks);
        assert!(fit.rounds() >= 2);
        for ((name, mask), t) in fit.masks().iter().zip(&truth) {
            assert_eq!(metrics::hard_iou(mask.unwrap(), t), 1.0, "{name}");
        }
        let r = fit.result(0.0, None).unwrap();
        assert_eq!(r.verdict, Some(Verdict::Ok));
        assert_eq!(r.masks.len(), 3);
    }

    #[test]
    fn wrong_answers_are_errors_not_panics() {
        let (scene, truth) = scene();
        let mut fit = PhotoFit::new(scene, FitSettings::default(), PhotoSettings::default()).unwrap();
        assert_eq!(fit.pending().len(), 3);
        let e = fit.answer(Vec::new()).unwrap_err().to_string();
        assert!(e.contains("0 answers for 3"), "{e}");
        let mut answers = Fake(truth.clone()).segment(fit.pending(), &[]).unwrap();
        answers[1].candidates[0].mask = Mask::empty(3, 3);
        let e = fit.answer(answers.clone()).unwrap_err().to_string();
        assert!(e.contains("view1"), "{e}");
        // Nothing was taken: the same jobs wait, and a good answer is still accepted.
        assert_eq!(fit.pending().len(), 3);
        answers[1].candidates[0].mask = answers[0].candidates[0].mask.clone();
        answers[1].preferred = 7;
        let e = fit.answer(answers).unwrap_err().to_string();
        assert!(e.contains("view1") && e.contains("preferred"), "{e}");
        assert!(fit.advance().is_err(), "advance before a fit");
        let good = Fake(truth).segment(fit.pending(), &[]).unwrap();
        fit.answer(good).unwrap();
        assert!(fit.estimator().is_some());
    }
}
