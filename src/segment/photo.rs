//! [`PhotoFit`]: photographs in, pose out. The masks a scene lacks are made by a
//! prompted segmenter and corrected by the fit itself, round by round:
//!
//! 0. every view without a mask gets a box (the user's, or the geometry's:
//!    [`super::hints`]) and a [`SegmentJob`] prompted with it;
//! 1. the masks the segmenter returns and the given ones are fitted (an [`Estimator`]
//!    the caller runs, from no initial pose) — in this first round without the views
//!    boxed by the geometry, when two others can be fitted;
//! 2. each made mask is asked for again from the fitted pose ([`prompt::from_pose`]):
//!    the silhouette's tight box, a point on the object, a point against the previous
//!    mask's excess, the previous mask as mask input — the views the fit doubts first —
//!    and the masks are refitted: from the previous pose when its verdict was `ok`, else
//!    searched afresh with the previous pose and its alternatives among the candidates;
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
use super::prompt::{self, Crop, MaskCandidate, PromptPoint, SegmentJob, SegmentOutput};
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
}

impl Default for PhotoSettings {
    fn default() -> Self {
        PhotoSettings {
            rounds: 2,
            crop_margin: 0.15,
            converged_iou: 0.98,
        }
    }
}

/// A user's point clicked within this many pixels of an earlier one removes it.
pub const POINT_TOGGLE_PX: f64 = 6.0;

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
    /// The user's points, image pixel centres, and whether each is on the object.
    points: Vec<(DVec2, bool)>,
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

/// One scene view's box, for a person drawing them (see [`PhotoFit::boxes`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ViewBox {
    /// The view's name.
    pub view: String,
    /// Whether the view has a mask already (given in the scene): it needs no box.
    pub has_mask: bool,
    /// The box drawn or given, image pixels `[x_min, y_min, x_max, y_max]`.
    pub given: Option<[f64; 4]>,
    /// For a view without one, the box the other views' geometry proposes (when at
    /// least two have a box or a mask).
    pub proposed: Option<[f64; 4]>,
    /// The user's points, `[x, y, 1 on the object | 0 off it]`, image pixel centres.
    pub points: Vec<[f64; 3]>,
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
                slots.push(Slot::Made(Made {
                    crop: Crop { x0: 0, y0: 0, side: 0 },
                    mask: None,
                    reference: None,
                    points: Vec::new(),
                    report: MaskReport {
                        view: p.name.clone(),
                        first_box_from: String::new(),
                        first_box: [0.0; 4],
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

    /// The sphere the hinted views' boxes and masks imply, when two or more have one.
    fn sphere(&self) -> Option<(glam::DVec3, f64)> {
        let hinted: Vec<(&crate::camera::Camera, PixelBox, &str)> = self
            .slots
            .iter()
            .filter_map(|s| match s {
                Slot::Given(v) => PixelBox::of_mask(v.mask()).map(|b| (v.camera(), b, v.name())),
                Slot::Made(m) => m.photo.hint.map(|b| (&m.photo.camera, b, m.photo.name.as_str())),
            })
            .collect();
        (hinted.len() >= 2).then(|| sphere_from_boxes(&hinted).ok()).flatten()
    }

    /// Every view's box: given (drawn, or in the scene) or proposed by the geometry,
    /// and its points, in scene order.
    pub fn boxes(&self) -> Vec<ViewBox> {
        let sphere = self.sphere();
        self.slots
            .iter()
            .map(|s| match s {
                Slot::Given(v) => ViewBox {
                    view: v.name().into(),
                    has_mask: true,
                    given: None,
                    proposed: None,
                    points: Vec::new(),
                },
                Slot::Made(m) => ViewBox {
                    view: m.photo.name.clone(),
                    has_mask: false,
                    given: m.photo.hint.map(|b| b.to_array()),
                    proposed: match (m.photo.hint, sphere) {
                        (None, Some((c, r))) => box_of_sphere(&m.photo.name, &m.photo.camera, c, r)
                            .ok()
                            .map(|b| b.to_array()),
                        _ => None,
                    },
                    points: m
                        .points
                        .iter()
                        .map(|(p, on)| [p.x, p.y, f64::from(u8::from(*on))])
                        .collect(),
                },
            })
            .collect()
    }

    /// Draws (or, with `None`, removes) view `view`'s box, image pixels
    /// `[x_min, y_min, x_max, y_max]`. Before the first round it is the box the view
    /// is first prompted with; once the rounds are over, the view is segmented again
    /// from it (its points kept) and the masks refitted.
    ///
    /// Errors: a bad box (named by view), a view with a mask, or a round under way.
    pub fn set_box(&mut self, view: usize, b: Option<[f64; 4]>) -> Result<()> {
        let state = self.state;
        if !matches!(state, State::Boxes | State::Done) {
            return Err(Error::Settings(
                "photographs: boxes can be changed before the fit starts or once it is done".into(),
            ));
        }
        let margin = self.photo.crop_margin;
        let m = self.made(view)?;
        let b = b
            .map(|b| PixelBox::new(&m.photo.name, b, m.photo.camera.width, m.photo.camera.height))
            .transpose()?;
        if state == State::Done {
            let Some(b) = b else {
                return Err(Error::View {
                    view: m.photo.name.clone(),
                    problem: "once fitted, a view's box can be redrawn but not removed".into(),
                });
            };
            m.crop = Crop::around(&b, margin);
            m.reference = None;
            let mut job = SegmentJob::from_box(view, m.crop, &b);
            add_points(&mut job, &m.points);
            self.pending = vec![job];
            self.state = State::Segment;
        }
        let m = self.made(view)?;
        m.photo.hint = b;
        Ok(())
    }

    /// Adds a point on (`object`) or off the object at image pixel `(x, y)` of view
    /// `view` — or, within [`POINT_TOGGLE_PX`] of one of its points, removes that one.
    /// Before the first round the points join the first prompts; once the rounds are
    /// over, the view is segmented again (prompted from the fitted pose and all its
    /// points) and the masks refitted.
    ///
    /// Errors: a point off the image or not finite, a view with a mask, or a round
    /// under way.
    pub fn toggle_point(&mut self, view: usize, x: f64, y: f64, object: bool) -> Result<()> {
        let state = self.state;
        if !matches!(state, State::Boxes | State::Done) {
            return Err(Error::Settings(
                "photographs: points can be added before the fit starts or once it is done".into(),
            ));
        }
        self.made(view)?;
        let (mesh, fitted, margin) = (&self.mesh, self.fitted, self.photo.crop_margin);
        let Some(Slot::Made(m)) = self.slots.get_mut(view) else {
            unreachable!("made() errs for every other slot");
        };
        let (w, h) = (m.photo.camera.width as f64, m.photo.camera.height as f64);
        if !(x.is_finite() && y.is_finite() && x > -0.5 && y > -0.5 && x < w - 0.5 && y < h - 0.5) {
            return Err(Error::View {
                view: m.photo.name.clone(),
                problem: format!("point ({x}, {y}) is not on the {w}×{h} photograph"),
            });
        }
        let p = DVec2::new(x, y);
        match m.points.iter().position(|(q, _)| (*q - p).length() <= POINT_TOGGLE_PX) {
            Some(i) => {
                m.points.remove(i);
            }
            None => m.points.push((p, object)),
        }
        if state == State::Done {
            let Some(pose) = fitted else {
                unreachable!("a done fit has a pose");
            };
            let job = reprompt(mesh, &pose, view, m, margin);
            self.pending = vec![job];
            self.state = State::Segment;
        }
        Ok(())
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
        let hinted = self
            .slots
            .iter()
            .filter(|s| matches!(s, Slot::Given(_)) || matches!(s, Slot::Made(m) if m.photo.hint.is_some()))
            .count();
        let unhinted = self.slots.iter().find_map(|s| match s {
            Slot::Made(m) if m.photo.hint.is_none() => Some(m.photo.name.clone()),
            _ => None,
        });
        let sphere = match unhinted {
            None => None,
            Some(name) if hinted < 2 => {
                return Err(Error::View {
                    view: name,
                    problem: format!(
                        "has neither a mask nor a box, and its box can only come from the geometry of at least \
                         two other views with a box or a mask (the scene has {hinted})"
                    ),
                })
            }
            Some(_) => {
                let hinted: Vec<(&crate::camera::Camera, PixelBox, &str)> = self
                    .slots
                    .iter()
                    .filter_map(|s| match s {
                        Slot::Given(v) => PixelBox::of_mask(v.mask()).map(|b| (v.camera(), b, v.name())),
                        Slot::Made(m) => m.photo.hint.map(|b| (&m.photo.camera, b, m.photo.name.as_str())),
                    })
                    .collect();
                Some(sphere_from_boxes(&hinted)?)
            }
        };
        let margin = self.photo.crop_margin;
        let mut jobs = Vec::new();
        for (i, s) in self.slots.iter_mut().enumerate() {
            let Slot::Made(m) = s else { continue };
            let b = match (m.photo.hint, sphere) {
                (Some(b), _) => b,
                (None, Some((c, r))) => box_of_sphere(&m.photo.name, &m.photo.camera, c, r)?,
                (None, None) => unreachable!("a sphere is made when a view has no box"),
            };
            m.report.first_box_from = if m.photo.hint.is_some() { "box" } else { "geometry" }.into();
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

    /// Before [`PhotoFit::start`], the first round's jobs of the views that have their
    /// box already — the same crops and prompts `start` will ask for — so that a
    /// segmenter can encode their crops while the other boxes are drawn. Empty once
    /// started.
    pub fn warm_jobs(&self) -> Vec<SegmentJob> {
        if self.state != State::Boxes {
            return Vec::new();
        }
        self.slots
            .iter()
            .enumerate()
            .filter_map(|(i, s)| match s {
                Slot::Made(m) => m.photo.hint.map(|b| {
                    let mut job = SegmentJob::from_box(i, Crop::around(&b, self.photo.crop_margin), &b);
                    add_points(&mut job, &m.points);
                    job
                }),
                Slot::Given(_) => None,
            })
            .collect()
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
            Some(Slot::Made(m)) => Some(&m.photo.image),
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
            let pick = choose(&masks, out.preferred, m.reference.take().as_ref(), &m.points);
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
        let est = self.round_fit()?;
        self.state = State::Fit;
        Ok(est)
    }

    /// The fit of this round's views: the given ones and every made mask with an
    /// object pixel the ignore mask leaves.
    fn round_fit(&mut self) -> Result<Estimator> {
        let mut views = Vec::with_capacity(self.slots.len());
        // In the first round a view boxed by the geometry sits out when two others can be
        // fitted: its rough square prompts the segmenter poorly, and the fit's
        // silhouette prompts it far better in the next round.
        let placed = self
            .slots
            .iter()
            .filter(|s| match s {
                Slot::Given(_) => true,
                Slot::Made(m) => m.photo.hint.is_some() && m.mask.as_ref().is_some_and(|(k, _)| k.area() > 0),
            })
            .count();
        let first = self.round == 1 && placed >= 2;
        for s in &self.slots {
            let v = match s {
                Slot::Given(v) => v.clone(),
                Slot::Made(m) if first && m.photo.hint.is_none() => continue,
                Slot::Made(m) => {
                    let Some((mask, _)) = m.mask.as_ref() else { continue };
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
        // The next fit starts from this pose when it was good; else it searches afresh,
        // this pose and its alternatives among the candidates.
        let ok = judgement.as_ref().is_some_and(|j| j.verdict == Verdict::Ok);
        let found: Vec<Pose> = std::iter::once(pose)
            .chain(fitted.alternatives().iter().map(|a| a.pose))
            .collect();
        (self.starts, self.seeds) = if ok { (found, Vec::new()) } else { (Vec::new(), found) };
        if self.converged || self.round > self.photo.rounds {
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

    /// How each made mask came about, with its IoU against the silhouette at `pose`
    /// (the fit's, when given).
    pub fn reports(&self, pose: Option<&Pose>) -> Vec<MaskReport> {
        self.slots
            .iter()
            .filter_map(|s| match s {
                Slot::Made(m) => {
                    let mut r = m.report.clone();
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

/// The user's points of a view, in a job's crop (those inside it).
fn add_points(job: &mut SegmentJob, points: &[(DVec2, bool)]) {
    let side = job.crop.side as f64;
    for &(p, object) in points {
        let at = job.crop.to_crop(p);
        if at.x >= 0.0 && at.y >= 0.0 && at.x < side && at.y < side {
            job.points.push(PromptPoint {
                at: at.to_array(),
                object,
            });
        }
    }
}

/// A made view's job from the fitted `pose` (module doc), with its user's points; sets
/// the silhouette its answer is chosen by.
fn reprompt(mesh: &Mesh, pose: &Pose, view: usize, m: &mut Made, margin: f64) -> SegmentJob {
    let silhouette = hard::render(mesh, pose, &m.photo.camera);
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
        // The pose puts the object outside this photograph: ask with the first box.
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

/// Which of the segmenter's masks to take: the one that keeps most of the user's
/// points on the right side; among those, the segmenter's choice or — once there is a
/// fit — the reading that agrees best with the fitted silhouette.
fn choose(
    masks: &[(Mask, MaskCandidate)],
    preferred: usize,
    reference: Option<&Mask>,
    points: &[(DVec2, bool)],
) -> usize {
    let kept = |m: &Mask| {
        points
            .iter()
            .filter(|(p, on)| {
                let (x, y) = (p.x.round(), p.y.round());
                let inside = x >= 0.0 && y >= 0.0 && m.get(x as u32, y as u32);
                inside == *on
            })
            .count()
    };
    let best_kept = masks.iter().map(|(m, _)| kept(m)).max().unwrap_or(0);
    let eligible = |i: &usize| kept(&masks[*i].0) == best_kept;
    match reference {
        Some(r) => (0..masks.len())
            .filter(eligible)
            .max_by(|&a, &b| metrics::hard_iou(&masks[a].0, r).total_cmp(&metrics::hard_iou(&masks[b].0, r)))
            .expect("candidates checked non-empty"),
        None if eligible(&preferred) => preferred,
        None => (0..masks.len())
            .filter(eligible)
            .max_by(|&a, &b| masks[a].1.score.total_cmp(&masks[b].1.score))
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
        let est = run(&mut fit, &mut Fake(truth.clone()), |_, _| {}).unwrap();
        let reports = fit.reports(Some(&est.pose()));
        // View 0: the segmenter's preference first, then the true reading, chosen by
        // the fitted silhouette; the other views had one reading each.
        assert_eq!(reports[0].picks.first(), Some(&0), "{:?}", reports[0].picks);
        assert_eq!(reports[0].picks.last(), Some(&1), "{:?}", reports[0].picks);
        assert!(fit.rounds() >= 2);
        for ((name, mask), t) in fit.masks().iter().zip(&truth) {
            assert_eq!(metrics::hard_iou(mask.unwrap(), t), 1.0, "{name}");
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
        // The warm jobs are the start's own, for the views with a box.
        let warm = fit.warm_jobs();
        assert_eq!(warm.len(), 2);
        fit.start().unwrap();
        assert_eq!(fit.pending().len(), 3);
        assert_eq!(&fit.pending()[..2], &warm[..]);
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
                    let mut m = self.truth[j.view].clone();
                    if self.calls == 1 && j.view == 2 {
                        let (w, h) = (m.width, m.height);
                        let moved: Vec<u8> = (0..w * h)
                            .map(|i| {
                                let (x, y) = (i % w, i / w);
                                if x >= 30 {
                                    self.truth[j.view].data[(y * w + x - 30) as usize]
                                } else {
                                    0
                                }
                            })
                            .collect();
                        m.data = moved;
                    }
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
}
