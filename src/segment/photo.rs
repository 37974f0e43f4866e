//! [`PhotoFit`]: photographs in, pose out. The masks a scene lacks are made by a
//! prompted segmenter and corrected by the fit itself, round by round:
//!
//! 0. every view without a mask gets a box (the user's, or the geometry's:
//!    [`super::hints`]) and a [`SegmentJob`] prompted with it;
//! 1. the masks the segmenter returns and the given ones are fitted (an [`Estimator`]
//!    the caller runs, from no initial pose) — in this first round without the views
//!    boxed by the geometry, when two others can be fitted; a made mask's contour
//!    distances capped ([`PhotoSettings::contour_cap`]), so that a thin part the
//!    segmenter missed costs a pose that shows it its area, not its reach;
//! 2. each made mask is asked for again from the fitted pose ([`prompt::from_pose`]):
//!    the silhouette's tight box, a point on the object, a point against the previous
//!    mask's excess, the previous mask as mask input — the silhouette kept within the
//!    view's drawn box, loosened ([`BOX_SLACK`]): the person said the object is in
//!    it, and a wrong fit must not lead the segmenter out of it — the views the fit
//!    doubts first —
//!    and the masks are refitted: from the previous pose when its verdict was `ok`, else
//!    searched afresh with the previous pose and its alternatives among the candidates
//!    (the second fit; from the third on, [`PhotoSettings::searches`], the previous
//!    pose and its alternatives are refined without a search);
//! 3. until every made mask changed by less than [`PhotoSettings::converged_iou`], or
//!    after [`PhotoSettings::rounds`] re-prompts.
//!
//! A person can step in: before the first round, draw or move the boxes
//! ([`PhotoFit::set_box`]; [`PhotoFit::boxes`] says which are given and which the
//! geometry proposes); after the last, add or remove a point on a view
//! ([`PhotoFit::toggle_point`]): that view is segmented again with its points and the
//! masks refitted.
//!
//! Like [`Estimator`], it is step-wise and does no inference itself: it names the
//! segmentations it needs ([`PhotoFit::pending`]), takes the answers
//! ([`PhotoFit::answer`], which hands back the round's fit to run) and, once that fit
//! is done, looks at it ([`PhotoFit::advance`]) — with a segmenter in this thread, a
//! pool of threads or the browser's Workers alike. [`run`] drives it with a
//! [`Segmenter`].

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
use boxes::add_points;
pub use boxes::{ViewBox, POINT_TOGGLE_PX};
use glam::DVec2;
use serde::{Deserialize, Serialize};

/// How masks are made and corrected.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PhotoSettings {
    /// Re-prompts from the fitted pose after the first fit (default 2).
    pub rounds: usize,
    /// The segmenter's square around a box: `1 + 2·margin` times its longest side
    /// (default 0.15: measured on the LM-O photographs, a tight crop seen as a 512²
    /// mosaic tile beat a wide one).
    pub crop_margin: f64,
    /// Masks that all changed less than this (IoU with the previous round's) end the
    /// rounds (default 0.98).
    pub converged_iou: f64,
    /// The contour loss's distances from a made mask are capped at this multiple of
    /// its equivalent radius ([`View::with_contour_cap`]; default 0.15): a segmenter
    /// misses thin parts (a spout) and fills holes (a handle's), and a pose that shows
    /// them should cost their area, not their reach. Measured on the LM-O photographs
    /// (tier2 `photos`): 27 → 29 of 32 fits within ADD(-S) < 0.1 d (the watering can
    /// no longer turned 177° with the first set of boxes), the masks' median IoU 0.807 →
    /// 0.815; with 0.1 or 0.3, 28 of 32. `None`: uncapped, as for given masks.
    pub contour_cap: Option<f64>,
    /// How many of the rounds' fits may search the orientations afresh (default 2).
    /// The first fit always searches; a later one searches when the previous fit's
    /// verdict was not `ok` and fewer than this many fits came before it; otherwise it
    /// refines the previous pose and its alternatives. A refit after the rounds (a
    /// point added, [`PhotoFit::toggle_point`]) searches when the last fit was not
    /// `ok`. Measured on the LM-O photographs (tier2 `photos`, 40 fits): 2 against 3
    /// (every fit in doubt searching) — the same 29 of 32 within ADD(-S) < 0.1 d,
    /// median ADD(-S) 4.37 against 4.42 % d, the median box-to-pose time 5.7–5.9 (two
    /// runs) against 6.6 s; 1 or 0 (the first fit only): 25 of 32.
    pub searches: usize,
}

impl Default for PhotoSettings {
    fn default() -> Self {
        PhotoSettings {
            rounds: 2,
            crop_margin: 0.15,
            converged_iou: 0.98,
            contour_cap: Some(0.15),
            searches: 2,
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
    /// Once the rounds are over, the mask returned when it is not the segmenter's: the
    /// fitted silhouette where the segmenter saw the object ([`visible`]).
    returned: Option<Mask>,
    /// The fitted pose's silhouette the pending job was prompted from (the segmenter's
    /// masks are chosen by it).
    reference: Option<Mask>,
    /// The user's points, image pixel centres, and whether each is on the object.
    points: Vec<(DVec2, bool)>,
    /// Its drawn box was too loose ([`boxes::LOOSE_BOX`]): the first round prompted it
    /// with the geometry's box instead, and its mask sat out the first fit.
    loose: bool,
    report: MaskReport,
}

/// Where the rounds stand.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum State {
    /// Before [`PhotoFit::start`]: boxes may be drawn.
    Boxes,
    /// Waiting for the segmenter's answers to `pending`.
    Segment,
    /// The caller runs the round's fit.
    Fit,
    /// Finished (until a point or a box asks for another round).
    Done,
}

/// Photographs in, pose out (module doc).
pub struct PhotoFit {
    mesh: Mesh,
    settings: FitSettings,
    photo: PhotoSettings,
    /// The poses the next round's fit starts from (none: it searches).
    starts: Vec<Pose>,
    /// The rotations the next round's search scores beside its own (the last fit's).
    seeds: Vec<Pose>,
    slots: Vec<Slot>,
    pending: Vec<SegmentJob>,
    state: State,
    /// Rounds of segmentation answered so far.
    round: usize,
    /// The last fit's pose, once there is one.
    fitted: Option<Pose>,
    converged: bool,
    warnings: Vec<String>,
}

impl PhotoFit {
    /// Starts on `scene`: boxes for every view without a mask, and the first jobs
    /// ([`PhotoFit::prepare`], then [`PhotoFit::start`]).
    ///
    /// Errors: those of both.
    pub fn new(scene: Scene, settings: FitSettings, photo: PhotoSettings) -> Result<PhotoFit> {
        let mut fit = PhotoFit::prepare(scene, settings, photo)?;
        fit.start()?;
        Ok(fit)
    }

    /// The rounds on `scene`, not started: its boxes may still be drawn.
    ///
    /// Errors: a scene without photographs to segment, invalid settings.
    pub fn prepare(scene: Scene, settings: FitSettings, photo: PhotoSettings) -> Result<PhotoFit> {
        settings.validate()?;
        if scene.photos.is_empty() {
            return Err(Error::Settings(
                "photographs: every view has a mask; nothing to segment".into(),
            ));
        }
        if !(photo.crop_margin >= 0.0
            && photo.crop_margin <= 4.0
            && photo.converged_iou > 0.0
            && photo.converged_iou <= 1.0
            && photo.contour_cap.is_none_or(|k| k.is_finite() && k > 0.0))
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
                slots.push(Slot::Made(Made {
                    crop: Crop { x0: 0, y0: 0, side: 0 },
                    mask: None,
                    returned: None,
                    reference: None,
                    points: Vec::new(),
                    loose: false,
                    report: MaskReport {
                        view: p.name.clone(),
                        first_box_from: String::new(),
                        first_box: [0.0; 4],
                        areas: Vec::new(),
                        changes: Vec::new(),
                        picks: Vec::new(),
                        score: 0.0,
                        iou_with_fit: 0.0,
                        returned: String::new(),
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
        Ok(PhotoFit {
            mesh: scene.mesh,
            settings,
            photo,
            starts: scene.initial_pose.into_iter().collect(),
            seeds: Vec::new(),
            slots,
            pending: Vec::new(),
            state: State::Boxes,
            round: 0,
            fitted: None,
            converged: false,
            warnings: Vec::new(),
        })
    }

    fn made(&mut self, view: usize) -> Result<&mut Made> {
        if let Some(Slot::Made(_)) = self.slots.get(view) {
            let Some(Slot::Made(m)) = self.slots.get_mut(view) else {
                unreachable!("just matched");
            };
            return Ok(m);
        }
        match self.slots.get(view) {
            Some(Slot::Made(_)) => unreachable!("returned above"),
            Some(Slot::Given(v)) => Err(Error::View {
                view: v.name().into(),
                problem: "has a mask already: it is not segmented".into(),
            }),
            None => Err(Error::Settings(format!(
                "photographs: no view {view} (the scene has {})",
                self.slots.len()
            ))),
        }
    }

    /// The first round: boxes for the views without one, from the others' boxes and
    /// masks, then a job per made view.
    ///
    /// Errors: called twice; a view with neither box nor mask when fewer than two
    /// others have one; boxes from the geometry that cannot be placed (named by view).
    pub fn start(&mut self) -> Result<()> {
        if self.state != State::Boxes {
            return Err(Error::Settings("photographs: the rounds have started already".into()));
        }
        let hinted = self.hinted();
        let unhinted = self.slots.iter().find_map(|s| match s {
            Slot::Made(m) if m.photo.hint.is_none() => Some(m.photo.name.clone()),
            _ => None,
        });
        let sphere = match unhinted {
            None => None,
            Some(name) if hinted.len() < 2 => {
                return Err(Error::View {
                    view: name,
                    problem: format!(
                        "has neither a mask nor a box, and its box can only come from the geometry of at least \
                         two other views with a box or a mask (the scene has {})",
                        hinted.len()
                    ),
                })
            }
            Some(_) => Some(sphere_from_boxes(&hinted)?),
        };
        let margin = self.photo.crop_margin;
        let loose = self.loose_boxes();
        let mut jobs = Vec::new();
        for ((i, s), loose) in self.slots.iter_mut().enumerate().zip(loose) {
            let Slot::Made(m) = s else { continue };
            let b = match (m.photo.hint, sphere, loose) {
                (Some(_), _, Some((within, ratio))) => {
                    self.warnings.push(format!(
                        "view '{}': the box drawn is {ratio:.1}× the size the other views' boxes imply (around the \
                         whole photograph?): the first round prompts the segmenter with the geometry's box within it \
                         and fits without this view",
                        m.photo.name
                    ));
                    m.loose = true;
                    within
                }
                (Some(b), _, None) => b,
                (None, Some((c, r)), _) => box_of_sphere(&m.photo.name, &m.photo.camera, c, r)?,
                (None, None, _) => unreachable!("a sphere is made when a view has no box"),
            };
            m.report.first_box_from = if m.photo.hint.is_some() && !m.loose {
                "box"
            } else {
                "geometry"
            }
            .into();
            m.report.first_box = b.to_array();
            m.crop = Crop::around(&b, margin);
            let mut job = SegmentJob::from_box(i, m.crop, &b);
            add_points(&mut job, &m.points);
            jobs.push(job);
        }
        self.pending = jobs;
        self.state = State::Segment;
        Ok(())
    }

    /// Whether [`PhotoFit::start`] has been called.
    pub fn is_started(&self) -> bool {
        self.state != State::Boxes
    }

    /// The segmentations the rounds wait for (empty while the caller fits, when done,
    /// or before the start).
    pub fn pending(&self) -> &[SegmentJob] {
        match self.state {
            State::Segment => &self.pending,
            _ => &[],
        }
    }

    /// The photograph of scene view `view` (for a segmenter), if it is a made one.
    pub fn image(&self, view: usize) -> Option<&Rgba> {
        match self.slots.get(view) {
            Some(Slot::Made(m)) => Some(m.photo.image.as_ref()),
            _ => None,
        }
    }

    /// The number of views (given and made), in scene order.
    pub fn view_count(&self) -> usize {
        self.slots.len()
    }

    /// Takes the answers to [`PhotoFit::pending`], in order, and returns the round's fit
    /// for the caller to run to its end, then to hand to [`PhotoFit::advance`].
    ///
    /// Errors: not waiting for answers, the wrong number of them, a mask of the wrong
    /// size, or no view left to fit. A wrong answer changes nothing: the same jobs wait.
    pub fn answer(&mut self, outputs: Vec<SegmentOutput>) -> Result<Estimator> {
        if self.state != State::Segment || outputs.len() != self.pending.len() {
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
        for s in &mut self.slots {
            if let Slot::Made(m) = s {
                m.returned = None;
            }
        }
        for (job, out) in std::mem::take(&mut self.pending).into_iter().zip(outputs) {
            let Some(Slot::Made(m)) = self.slots.get_mut(job.view) else {
                unreachable!("checked above");
            };
            let (w, h) = (m.photo.camera.width, m.photo.camera.height);
            let mut candidates = out.candidates;
            let pick = choose(
                &job.crop,
                &candidates,
                out.preferred,
                m.reference.take().as_ref(),
                &m.points,
                (w, h),
            );
            m.report.picks.push(pick);
            let chosen = candidates.swap_remove(pick);
            let mask = job.crop.to_image(&chosen.mask, w, h);
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
        let est = self.round_fit()?;
        self.state = State::Fit;
        Ok(est)
    }

    /// The fit of this round's views: the given ones and every made mask with an
    /// object pixel the ignore mask leaves.
    fn round_fit(&mut self) -> Result<Estimator> {
        let mut views = Vec::with_capacity(self.slots.len());
        // In the first round a view boxed by the geometry (no box, or one too loose)
        // sits out when two others can be fitted: its rough square prompts the
        // segmenter poorly, and the fit's silhouette prompts it far better in the next
        // round.
        let placed = self
            .slots
            .iter()
            .filter(|s| match s {
                Slot::Given(_) => true,
                Slot::Made(m) => {
                    m.photo.hint.is_some() && !m.loose && m.mask.as_ref().is_some_and(|(k, _)| k.area() > 0)
                }
            })
            .count();
        let first = self.round == 1 && placed >= 2;
        for s in &self.slots {
            let v = match s {
                Slot::Given(v) => v.clone(),
                Slot::Made(m) if first && (m.photo.hint.is_none() || m.loose) => continue,
                Slot::Made(m) => {
                    let Some((mask, _)) = m.mask.as_ref() else { continue };
                    let p = &m.photo;
                    let cover = mask.area() as f64 / (mask.width as f64 * mask.height as f64);
                    if cover >= WHOLE_MASK {
                        let said = format!("view '{}': the segmenter's mask covers", p.name);
                        if !self.warnings.iter().any(|w| w.starts_with(&said)) {
                            self.warnings.push(format!(
                                "{said} {:.0} % of the photograph, which says little of where the object is: draw \
                                 a box close around the object",
                                100.0 * cover
                            ));
                        }
                    }
                    let sources = ViewSources::files("(made by the segmenter)", "ignore mask", "photograph");
                    match View::sharing(
                        &p.name,
                        p.camera,
                        mask.clone(),
                        p.ignore.clone(),
                        Some(p.image.clone()),
                        &sources,
                    ) {
                        Ok(v) => match self.photo.contour_cap {
                            Some(k) => v.with_contour_cap(k).with_colour_refinement(),
                            None => v.with_colour_refinement(),
                        },
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
        }
        if views.is_empty() {
            return Err(Error::Settings(
                "photographs: the segmenter found the object in no view: check the boxes".into(),
            ));
        }
        if self.starts.is_empty() {
            Estimator::with_seeds(self.mesh.clone(), views, &self.seeds, self.settings.clone())
        } else {
            Estimator::from_starts(self.mesh.clone(), views, self.starts.clone(), self.settings.clone())
        }
    }

    /// Looks at the round's finished fit: re-prompts from its pose (module doc), or
    /// ends the rounds.
    ///
    /// Errors: no round's fit under way, or `fitted` not done.
    pub fn advance(&mut self, fitted: &Estimator) -> Result<()> {
        if self.state != State::Fit || !fitted.is_done() {
            return Err(Error::Settings(
                "photographs: advance is for the round's fit once it is done".into(),
            ));
        }
        let pose = fitted.pose();
        self.fitted = Some(pose);
        let judgement = fitted.judgement().cloned();
        // The next fit starts from this pose when it was good, or when enough fits have
        // searched (a refit after the rounds, for a person's point, always may); else it
        // searches afresh, this pose and its alternatives among the candidates.
        let ok = judgement.as_ref().is_some_and(|j| j.verdict == Verdict::Ok);
        let last = self.converged || self.round > self.photo.rounds;
        let search = !ok && (last || self.round < self.photo.searches);
        let found: Vec<Pose> = std::iter::once(pose)
            .chain(fitted.alternatives().iter().map(|a| a.pose))
            .collect();
        (self.starts, self.seeds) = if search {
            (Vec::new(), found)
        } else {
            (found, Vec::new())
        };
        if last {
            self.return_visible(&pose);
            self.state = State::Done;
            return Ok(());
        }
        // How much the fit trusts each view: doubted by the verdict, its robust weight,
        // its IoU at the pose (a view that sat the round out: not at all).
        let doubted: Vec<String> = judgement.map(|j| j.doubted_views).unwrap_or_default();
        let weights = fitted.view_weights().map(<[f64]>::to_vec).unwrap_or_default();
        let figures = fitted.view_figures(&pose);
        let trust = |name: &str| -> (bool, f64, f64) {
            match fitted.views().iter().position(|v| v.name() == name) {
                Some(k) => (
                    !doubted.iter().any(|d| d == name),
                    weights.get(k).copied().unwrap_or(1.0),
                    figures.get(k).map_or(0.0, |f| f.iou),
                ),
                None => (false, 0.0, 0.0),
            }
        };
        let margin = self.photo.crop_margin;
        let mut jobs = Vec::new();
        for (i, s) in self.slots.iter_mut().enumerate() {
            let Slot::Made(m) = s else { continue };
            let t = trust(&m.photo.name);
            jobs.push((t, reprompt(&self.mesh, &pose, i, m, margin)));
        }
        // The views the fit doubts first: named by the verdict, then by robust weight,
        // then by IoU, least trusted first.
        jobs.sort_by(|(a, _), (b, _)| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)).then(a.2.total_cmp(&b.2)));
        self.pending = jobs.into_iter().map(|(_, j)| j).collect();
        self.state = State::Segment;
        Ok(())
    }

    /// The masks to return, once the rounds are over: each made view's silhouette at
    /// the final `pose` where the segmenter saw the object ([`visible`]) — unless the
    /// two disagree (IoU below 0.5) or nothing would be left: then the segmenter's own.
    fn return_visible(&mut self, pose: &Pose) {
        for s in &mut self.slots {
            let Slot::Made(m) = s else { continue };
            let Some((mask, _)) = &m.mask else { continue };
            let silhouette = hard::render(&self.mesh, pose, &m.photo.camera);
            if metrics::hard_iou(mask, &silhouette) >= 0.5 {
                let v = visible::visible(&silhouette, mask);
                m.returned = (v.area() > 0).then_some(v);
            }
        }
    }

    /// Whether the rounds are over.
    pub fn is_done(&self) -> bool {
        self.state == State::Done
    }

    /// Whether the caller should be running the round's fit (between
    /// [`PhotoFit::answer`] and [`PhotoFit::advance`]).
    pub fn is_fitting(&self) -> bool {
        self.state == State::Fit
    }

    /// Segmentation rounds answered so far.
    pub fn rounds(&self) -> usize {
        self.round
    }

    /// Each scene view's mask as it stands, with the view's name, in scene order: given,
    /// or made — the segmenter's during the rounds (`None` before it is made), and once
    /// they are over, the fitted silhouette where the segmenter saw the object
    /// ([`visible`]; [`MaskReport::returned`] says which).
    pub fn masks(&self) -> Vec<(&str, Option<&Mask>)> {
        self.slots
            .iter()
            .map(|s| match s {
                Slot::Given(v) => (v.name(), Some(v.mask())),
                Slot::Made(m) => (
                    m.photo.name.as_str(),
                    m.returned.as_ref().or(m.mask.as_ref().map(|(k, _)| k)),
                ),
            })
            .collect()
    }

    /// As [`PhotoFit::masks`], but each made view's latest mask from the segmenter
    /// even after the rounds (what the fits were given).
    pub fn segmenter_masks(&self) -> Vec<(&str, Option<&Mask>)> {
        self.slots
            .iter()
            .map(|s| match s {
                Slot::Given(v) => (v.name(), Some(v.mask())),
                Slot::Made(m) => (m.photo.name.as_str(), m.mask.as_ref().map(|(k, _)| k)),
            })
            .collect()
    }

    /// How each made mask came about, with its IoU against the silhouette at `pose`
    /// (the fit's, when given).
    pub fn reports(&self, pose: Option<&Pose>) -> Vec<MaskReport> {
        self.slots
            .iter()
            .filter_map(|s| match s {
                Slot::Made(m) => {
                    let mut r = m.report.clone();
                    r.returned = if m.returned.is_some() { "fit" } else { "segmenter" }.into();
                    if let (Some(p), Some((mask, _))) = (pose, &m.mask) {
                        r.iou_with_fit = metrics::hard_iou(mask, &hard::render(&self.mesh, p, &m.photo.camera));
                    }
                    Some(r)
                }
                Slot::Given(_) => None,
            })
            .collect()
    }

    /// The result of `fitted` (a round's fit), with the made masks' reports (SPEC §3).
    pub fn result(&self, fitted: &Estimator, seconds: f64, ground_truth: Option<&Pose>) -> FitResult {
        let mut r = fitted.result(seconds, ground_truth);
        r.masks = self.reports(Some(&fitted.pose()));
        r
    }

    /// What was accepted with a reservation (a view that sat a round out).
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }
}

/// A made mask covering at least this fraction of its photograph gets a warning (a
/// box around the whole photograph, with no other views to correct it).
const WHOLE_MASK: f64 = 0.9;

/// How far beyond a drawn box (a fraction of its longer side, each way, and 2 px) a
/// re-prompt may reach: a box need not be tight, one drawn a little inside the
/// object's edge still holds it, and one drawn around the visible part of an occluded
/// object leaves the hidden part's silhouette outside it. Measured on the LM-O
/// photographs (tier2 `photos`): 0.1 cost the partly hidden cat 0.1–0.3 % d in all
/// four of its fits, 0.3 and 0.5 nothing (every fit as without the limit).
pub const BOX_SLACK: f64 = 0.3;

/// `silhouette` without its pixels outside `b` loosened by [`BOX_SLACK`].
fn keep_within(silhouette: &mut Mask, b: &PixelBox) {
    let slack = BOX_SLACK * (b.x1 - b.x0).max(b.y1 - b.y0) + 2.0;
    let (x0, y0, x1, y1) = (b.x0 - slack, b.y0 - slack, b.x1 + slack, b.y1 + slack);
    let w = silhouette.width as usize;
    for (i, v) in silhouette.data.iter_mut().enumerate() {
        let (x, y) = ((i % w) as f64, (i / w) as f64);
        if x + 1.0 <= x0 || x >= x1 || y + 1.0 <= y0 || y >= y1 {
            *v = 0;
        }
    }
}

/// A made view's job from the fitted `pose` (module doc), with its user's points; sets
/// the silhouette its answer is chosen by.
fn reprompt(mesh: &Mesh, pose: &Pose, view: usize, m: &mut Made, margin: f64) -> SegmentJob {
    let mut silhouette = hard::render(mesh, pose, &m.photo.camera);
    if let Some(b) = &m.photo.hint {
        keep_within(&mut silhouette, b);
    }
    let tight = PixelBox::of_mask(&silhouette);
    // The square must hold the silhouette and the user's points.
    let reach = tight.map(|b| {
        m.points.iter().fold(b, |b, (p, _)| PixelBox {
            x0: b.x0.min(p.x),
            y0: b.y0.min(p.y),
            x1: b.x1.max(p.x + 1.0),
            y1: b.y1.max(p.y + 1.0),
        })
    });
    // A new square when the silhouette left the old one or shrank within it (the
    // previous logits are then of another crop).
    let keep = reach.is_some_and(|b| m.crop.holds(&b, 0.05, 0.25));
    if !keep {
        if let Some(b) = reach {
            m.crop = Crop::around(&b, margin);
        }
    }
    let previous = m
        .mask
        .as_ref()
        .filter(|_| keep)
        .map(|(mask, logits)| (mask, logits.as_slice()));
    let mut job = prompt::from_pose(view, m.crop, &silhouette, previous).unwrap_or_else(|| {
        // The pose puts the object outside this photograph (or outside the drawn
        // box): ask with the first box.
        let b = PixelBox {
            x0: m.report.first_box[0],
            y0: m.report.first_box[1],
            x1: m.report.first_box[2],
            y1: m.report.first_box[3],
        };
        m.crop = Crop::around(&b, margin);
        SegmentJob::from_box(view, m.crop, &b)
    });
    add_points(&mut job, &m.points);
    m.reference = tight.is_some().then_some(silhouette);
    job
}

/// Which of the segmenter's masks (of `crop`, in an image of `w × h`) to take: the one
/// that keeps most of the user's points on the right side; among those, the
/// segmenter's choice or — once there is a fit — the reading that agrees best with the
/// fitted silhouette (compared within the crop: [`Crop::iou_in_image`]).
fn choose(
    crop: &Crop,
    candidates: &[MaskCandidate],
    preferred: usize,
    reference: Option<&Mask>,
    points: &[(DVec2, bool)],
    (w, h): (u32, u32),
) -> usize {
    let kept = |m: &Mask| {
        points
            .iter()
            .filter(|(p, on)| {
                let (x, y) = (p.x.round(), p.y.round());
                let in_image = x >= 0.0 && y >= 0.0 && x < w as f64 && y < h as f64;
                let inside = in_image && crop.holds_pixel(m, x as i64, y as i64);
                inside == *on
            })
            .count()
    };
    let best_kept = candidates.iter().map(|c| kept(&c.mask)).max().unwrap_or(0);
    let eligible = |i: &usize| kept(&candidates[*i].mask) == best_kept;
    match reference {
        Some(r) => {
            let area = r.area();
            let iou: Vec<f64> = candidates.iter().map(|c| crop.iou_in_image(&c.mask, r, area)).collect();
            (0..candidates.len())
                .filter(eligible)
                .max_by(|&a, &b| iou[a].total_cmp(&iou[b]))
                .expect("candidates checked non-empty")
        }
        None if eligible(&preferred) => preferred,
        None => (0..candidates.len())
            .filter(eligible)
            .max_by(|&a, &b| candidates[a].score.total_cmp(&candidates[b].score))
            .expect("candidates checked non-empty"),
    }
}

/// Drives `fit` to the end with `segmenter` (starting it if it was only prepared),
/// calling `progress` after every segmentation round (with the fit about to run) and
/// every fit (done). Returns the last fit.
///
/// Errors: the segmenter's, the fit's.
pub fn run(
    fit: &mut PhotoFit,
    segmenter: &mut dyn Segmenter,
    mut progress: impl FnMut(&PhotoFit, &Estimator),
) -> Result<Estimator> {
    if !fit.is_started() {
        fit.start()?;
    }
    loop {
        let jobs = fit.pending().to_vec();
        let images: Vec<&Rgba> = jobs
            .iter()
            .map(|j| fit.image(j.view).expect("jobs are for made views"))
            .collect();
        let outputs = segmenter.segment(&jobs, &images)?;
        let mut est = fit.answer(outputs)?;
        progress(fit, &est);
        est.run(usize::MAX)?;
        fit.advance(&est)?;
        progress(fit, &est);
        if fit.is_done() {
            return Ok(est);
        }
    }
}

mod boxes;
#[cfg(test)]
mod tests;
pub mod visible;
