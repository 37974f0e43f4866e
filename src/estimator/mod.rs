//! The pipeline as a step-wise object (SPEC §4): initialise, search orientations,
//! refine the best candidates coarse-to-fine, judge. [`Estimator::step`] does one
//! small unit of work (a batch of search candidates or one optimiser iteration) so
//! that a UI can show every iteration; the state keeps the best pose so far. The
//! same object, with the same [`FitSettings::default`], drives the command line, the
//! browser and the npm package.
//!
//! A step is a [`Request`] answered by a [`Worker`](shard) and completed by
//! [`Estimator::respond`]: `step` answers it here, a pool of [`Shard`]s elsewhere, with
//! the same code ([`shard`] module doc). Every stage works on the views' windows
//! ([`crate::WindowMode`]) through one [`crate::loss::objective::Objective`]: the search
//! scores its hard IoUs, the stages descend `λ1·IoU + λ2·contour` with
//! Levenberg–Marquardt (its Gauss–Newton model) or Adam. The estimator is in one of
//! three states — searching, refining, done — and the final figures, the verdict and
//! the uncertainty are computed once, when it is done ([`finish`]).

use crate::error::{Error, Result};
use crate::loss::objective::ViewPart;
use crate::mesh::Mesh;
use crate::optim::init;
use crate::optim::search::{self, Candidate};
use crate::pose::Pose;
use crate::view::View;
use crate::window::Window;
use glam::{DMat3, DVec3};

mod cameras;
mod finish;
mod refine;
mod result;
mod robust;
mod settings;
mod setup;
mod shard;

pub use cameras::{CameraCorrection, CameraPrior, CameraTest};
pub use finish::{competes, Alternative, ViewFigures, ALTERNATIVE_FACTOR, ALTERNATIVE_SLACK};
pub use result::{AlternativeOut, FitResult, MaskReport, PoseOut, ViewResult};
pub use settings::{FitSettings, Phase, Progress, Termination, OBJECT_MARGIN};
pub use setup::FitSetup;
pub use shard::{Request, Response, Shard};

use finish::Final;
use refine::Refinement;
use shard::Worker;

/// Search candidates scored per step.
const SEARCH_BATCH: usize = 16;

/// Where the fit stands.
enum State {
    /// Scoring the search's rotations from `start`; `scored` holds those done so far.
    Search { start: Pose, scored: Vec<Candidate> },
    /// Refining the kept candidates, stage by stage.
    Refine(Refinement),
    /// Finished: the final pose, figures, verdict and uncertainty.
    Done(Box<Final>),
}

/// The step-wise pose estimator.
pub struct Estimator {
    setup: FitSetup,
    /// Answers this estimator's requests, over every view (and holds the objectives the
    /// estimator combines, ranks and polishes with).
    local: Worker,
    state: State,
    /// Optimiser iterations so far (all candidates, all stages).
    iterations: usize,
    /// The loss of the last iteration.
    last_loss: f64,
    /// The views as given, once the setup holds the corrected cameras.
    input_views: Option<Vec<View>>,
    /// Whether the search ran (not when an initial pose was given).
    searching: bool,
}

impl Estimator {
    /// Sets up a fit of `mesh` to `views`. With `initial_pose`, the search is skipped.
    ///
    /// Errors: invalid settings or mesh, no views, or an object whose centre is
    /// behind a camera at the initial pose.
    pub fn new(mesh: Mesh, views: Vec<View>, initial_pose: Option<Pose>, settings: FitSettings) -> Result<Estimator> {
        Estimator::from_starts(mesh, views, initial_pose.into_iter().collect(), settings)
    }

    /// Sets up a fit of `mesh` to `views` whose search also scores the rotations of
    /// `seeds` (e.g. an earlier fit's pose and its alternatives) beside its own sampling:
    /// the fit can keep what an earlier one found and still find better.
    ///
    /// Errors: as [`Estimator::new`].
    pub fn with_seeds(mesh: Mesh, views: Vec<View>, seeds: &[Pose], settings: FitSettings) -> Result<Estimator> {
        let mut est = Estimator::from_starts(mesh, views, Vec::new(), settings)?;
        est.setup.rotations.extend(seeds.iter().map(|p| p.rotation));
        Ok(est)
    }

    /// Sets up a fit of `mesh` to `views` that refines every pose of `starts` (e.g. an
    /// earlier fit's pose and its alternatives), each a candidate as the search's best
    /// would be; with no start, the search runs as in [`Estimator::new`].
    ///
    /// Errors: as [`Estimator::new`], for every start.
    pub fn from_starts(mesh: Mesh, views: Vec<View>, starts: Vec<Pose>, settings: FitSettings) -> Result<Estimator> {
        let setup = FitSetup::new(mesh, views, settings)?;
        let mut est = Estimator {
            local: Worker::new((0..setup.views.len()).collect()),
            setup,
            state: State::Search {
                start: Pose::IDENTITY,
                scored: Vec::new(),
            },
            iterations: 0,
            last_loss: f64::NAN,
            input_views: None,
            searching: starts.is_empty(),
        };
        match starts.is_empty() {
            false => {
                for p in &starts {
                    p.validate()?;
                    est.check_in_front(p)?;
                }
                est.begin_refine(starts, None)?;
            }
            true => {
                let start = est.initial_guess()?;
                est.local.search_objective(&est.setup)?;
                est.state = State::Search {
                    start,
                    scored: Vec::new(),
                };
            }
        }
        Ok(est)
    }

    /// The mesh being fitted.
    pub fn mesh(&self) -> &Mesh {
        self.setup.mesh()
    }

    /// The views being fitted (once done with `refine_cameras`, with the corrected
    /// cameras).
    pub fn views(&self) -> &[View] {
        &self.setup.views
    }

    /// The views as given (before any camera correction).
    pub fn input_views(&self) -> &[View] {
        self.input_views.as_deref().unwrap_or(&self.setup.views)
    }

    /// Each view's window.
    pub fn windows(&self) -> &[Window] {
        &self.setup.windows
    }

    /// The settings in use.
    pub fn settings(&self) -> &FitSettings {
        &self.setup.settings
    }

    /// The phase and refinement stage the next step will work in.
    pub fn progress_phase(&self) -> (Phase, usize) {
        match &self.state {
            State::Search { .. } => (Phase::Search, 0),
            State::Refine(r) => (Phase::Refine, r.stage),
            State::Done(_) => (Phase::Done, self.setup.settings.stages.len() - 1),
        }
    }

    /// Whether the fit has finished.
    pub fn is_done(&self) -> bool {
        matches!(self.state, State::Done(_))
    }

    /// The starting pose of the search: the centre triangulated from the masks, the
    /// scale 1 (the CAD model is to scale) or from the masks' areas.
    fn initial_guess(&self) -> Result<Pose> {
        let mean_area = (init::surface_area(self.mesh()) / 4.0).max(1e-300);
        // One view: the depth at which a unit-scale object covers the mask's area.
        let depth = |v: &View| {
            let c = v.camera();
            (c.fx * c.fy * mean_area / v.known_area().max(1) as f64).sqrt()
        };
        let x = init::triangulate_centre(&self.setup.views, depth)?;
        let s = if self.setup.settings.scale_mode.fits_scale() {
            init::scale_from_areas(&self.setup.views, x, mean_area)
        } else {
            1.0
        };
        let scale = DVec3::splat(s);
        let pose = Pose {
            rotation: DMat3::IDENTITY,
            translation: x - scale * self.setup.centre,
            scale,
        };
        self.check_in_front(&pose)?;
        Ok(pose)
    }

    /// An error naming the first view that sees the object's centre behind it.
    fn check_in_front(&self, pose: &Pose) -> Result<()> {
        let c = pose.apply(self.setup.centre);
        for v in &self.setup.views {
            if v.camera().to_camera(c).z <= 0.0 {
                return Err(Error::View {
                    view: v.name().to_string(),
                    problem: "the object's centre is behind this camera (check the camera's extrinsics and convention)"
                        .into(),
                });
            }
        }
        Ok(())
    }

    /// Does one unit of work — [`Estimator::request`], answered here by the same
    /// function a [`Shard`] runs, then [`Estimator::respond`] — and reports where the fit
    /// stands. To keep a step cheap, its `view_iou` is left empty:
    /// [`Estimator::progress`] fills it.
    ///
    /// Errors: none on validated inputs; an internal failure (a bug) is reported
    /// rather than hidden, and the estimator then stays where it was.
    pub fn step(&mut self) -> Result<Progress> {
        match self.request() {
            Some(request) => {
                let response = self.local.work(&self.setup, &request)?;
                self.respond(vec![response])
            }
            None => Ok(self.snapshot(Vec::new())),
        }
    }

    /// The work the next step needs, to be computed by a [`Shard`] (here, by
    /// [`Estimator::step`]; elsewhere, by other threads or Web Workers) and handed back
    /// with [`Estimator::respond`]; `None` when the fit is done.
    pub fn request(&self) -> Option<Request> {
        match &self.state {
            State::Search { start, scored } => {
                let first = scored.len();
                Some(Request::Search {
                    start: *start,
                    first,
                    count: SEARCH_BATCH.min(self.setup.rotations.len() - first),
                })
            }
            State::Refine(r) => Some(r.request(&self.setup, &self.local)),
            State::Done(_) => None,
        }
    }

    /// Completes the step [`Estimator::request`] asked for, with the responses to it
    /// (for an evaluation, together every view's part, once; for a search batch, every
    /// rotation of it).
    ///
    /// Errors: responses that do not answer the current request (the estimator then
    /// stays where it was).
    pub fn respond(&mut self, responses: Vec<Response>) -> Result<Progress> {
        let bad = |m: String| Err(Error::Settings(format!("respond: {m}")));
        match self.request() {
            Some(Request::Search { first, count, .. }) => {
                let mut batches: Vec<(usize, Vec<Candidate>)> = Vec::new();
                for r in responses {
                    match r {
                        Response::Candidates { first, candidates } => {
                            for c in &candidates {
                                c.pose.validate()?;
                            }
                            batches.push((first, candidates))
                        }
                        Response::Parts { .. } => return bad("view parts for a search batch".into()),
                    }
                }
                batches.sort_by_key(|b| b.0);
                let mut next = first;
                let mut all = Vec::with_capacity(count);
                for (f, c) in batches {
                    if f != next {
                        return bad(format!("search rotations from {f}, expected {next}"));
                    }
                    next += c.len();
                    all.extend(c);
                }
                if all.len() != count {
                    return bad(format!("{} candidates for a batch of {count}", all.len()));
                }
                self.finish_search_batch(all)?;
            }
            Some(Request::Evaluate { .. }) => {
                let n = self.setup.views.len();
                let mut parts: Vec<Option<ViewPart>> = vec![None; n];
                for r in responses {
                    match r {
                        Response::Parts { views, parts: p } if views.len() == p.len() => {
                            for (v, part) in views.into_iter().zip(p) {
                                match parts.get_mut(v) {
                                    Some(slot @ None) => *slot = Some(part),
                                    _ => return bad(format!("view {v} twice or beyond the {n} views")),
                                }
                            }
                        }
                        _ => return bad("not one part per view named".into()),
                    }
                }
                let parts: Option<Vec<ViewPart>> = parts.into_iter().collect();
                let Some(parts) = parts else {
                    return bad("some views have no part".into());
                };
                self.refine_apply(&parts)?;
            }
            None => return bad("the fit is done".into()),
        }
        Ok(self.snapshot(Vec::new()))
    }

    /// Steps until done (at most `max_steps`); returns the last progress.
    pub fn run(&mut self, max_steps: usize) -> Result<Progress> {
        for _ in 0..max_steps {
            if self.is_done() {
                break;
            }
            self.step()?;
        }
        Ok(self.progress())
    }

    /// Takes a batch of scored candidates (the next rotations in order); after the
    /// last batch, keeps the best and starts the refinement.
    fn finish_search_batch(&mut self, batch: Vec<Candidate>) -> Result<()> {
        let State::Search { start, scored } = &mut self.state else {
            return Err(Error::Settings("internal: a search batch outside the search".into()));
        };
        scored.extend(batch);
        if scored.len() < self.setup.rotations.len() {
            return Ok(());
        }
        let start = *start;
        let s = &self.setup.settings.search;
        let best = search::select_best(std::mem::take(scored), s.keep, s.min_separation_deg);
        let poses: Vec<Pose> = best.iter().map(|c| c.pose).collect();
        if poses.is_empty() {
            return self.begin_refine(vec![start], None);
        }
        let losses: Vec<Vec<f64>> = best.iter().map(|c| c.ious.iter().map(|i| 1.0 - i).collect()).collect();
        self.begin_refine(poses, Some(losses))
    }

    /// The pose the fit currently holds (the best so far once done).
    pub fn pose(&self) -> Pose {
        match &self.state {
            State::Search { start, scored } => scored
                .iter()
                .max_by(|a, b| a.score.total_cmp(&b.score))
                .map_or(*start, |c| c.pose),
            State::Refine(r) => r.tracks[r.current].pose,
            State::Done(f) => f.pose,
        }
    }

    /// A snapshot of the state, with the full-resolution hard IoU of every view at the
    /// current pose ([`Estimator::view_ious`]).
    pub fn progress(&self) -> Progress {
        let ious = self.view_ious(&self.pose());
        self.snapshot(ious)
    }

    fn snapshot(&self, view_iou: Vec<f64>) -> Progress {
        let (phase, stage) = self.progress_phase();
        let total = if self.searching { self.setup.rotations.len() } else { 0 };
        let (searched, candidate) = match &self.state {
            State::Search { scored, .. } => (scored.len(), 0),
            State::Refine(r) => (total, r.current),
            State::Done(_) => (total, 0),
        };
        let done = match &self.state {
            State::Done(f) => Some(f),
            _ => None,
        };
        Progress {
            phase,
            iteration: self.iterations,
            searched,
            search_total: total,
            stage,
            candidate,
            loss: self.last_loss,
            view_iou,
            pose: self.pose(),
            termination: done.map(|f| f.termination),
            verdict: done.map(|f| f.judgement.verdict),
        }
    }
}
