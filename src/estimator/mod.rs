//! The pipeline as a step-wise object (SPEC §4): initialise, search orientations,
//! refine the best candidates coarse-to-fine, judge. [`Estimator::step`] does one
//! small unit of work (a batch of search candidates or one optimiser iteration) so
//! that a UI can show every iteration; the state keeps the best pose so far. The
//! same object, with the same [`FitSettings::default`], drives the command line, the
//! browser and the npm package.
//!
//! Every stage works on the views' windows ([`WindowMode`]) through one
//! [`Objective`]: the search scores its hard IoUs, the stages descend
//! `λ1·IoU + λ2·contour` with Levenberg–Marquardt (its Gauss–Newton model) or Adam.

use crate::error::{Error, Result};
use crate::loss::objective::{Objective, PartKind, ViewPart};
use crate::loss::target::Window;
use crate::mask::Mask;
use crate::mesh::Mesh;
use crate::metrics;
use crate::optim::adam::Adam;
use crate::optim::lm::{self, Lm};
use crate::optim::schedule::Optimiser;
use crate::optim::search::{self, Candidate};
use crate::optim::{init, params};
use crate::pose::Pose;
use crate::raster::hard::{self, BitMask};
use crate::raster::silhouette::RenderMesh;
use crate::uncertainty::{
    candidate_viewpoints, fit_uncertainty, next_view, rank_views, sphere_candidates, std_dev, NoiseModel, RankedView,
    Uncertainty, Viewpoints,
};
use crate::verdict::{self, Judgement, Verdict};
use crate::view::View;
use glam::{DMat3, DVec3};

mod cameras;
mod robust;
mod settings;
mod shard;

pub use cameras::{CameraCorrection, CameraPrior, CameraTest};
pub use robust::robust_weights;
pub use settings::{FitSettings, Phase, Progress, ScaleMode, Termination, OBJECT_MARGIN};
pub use shard::{Request, Response, Shard};

use robust::{free_parameters, leave_one_out};
use shard::score_rotations;

/// One candidate being refined.
#[derive(Debug, Clone)]
struct Track {
    pose: Pose,
    adam: Adam,
    lm: Lm,
    best_pose: Pose,
    best_loss: f64,
    since_best: usize,
    history: Vec<f64>,
    done_in_stage: bool,
    converged: bool,
    /// The views' weights in this candidate's objective (robust re-weighting).
    weights: Vec<f64>,
    /// Views the leave-one-out test found to contradict the others (weight 0).
    excluded: Vec<bool>,
}

impl Track {
    fn new(pose: Pose, views: usize) -> Track {
        Track {
            weights: vec![1.0; views],
            excluded: vec![false; views],
            pose,
            adam: Adam::new(),
            lm: Lm::new(),
            best_pose: pose,
            best_loss: f64::INFINITY,
            since_best: 0,
            history: Vec::new(),
            done_in_stage: false,
            converged: false,
        }
    }

    /// Appends a loss to the history and keeps the best pose.
    fn record(&mut self, loss: f64) {
        self.history.push(loss);
        if loss < self.best_loss {
            self.best_loss = loss;
            self.best_pose = self.pose;
            self.since_best = 0;
        } else {
            self.since_best += 1;
        }
    }
}

/// A view's figures at full resolution.
#[derive(Debug, Clone)]
pub struct ViewFigures {
    /// Hard IoU over the known pixels.
    pub iou: f64,
    /// Hausdorff distance between the rendered and the mask's contours, pixels.
    pub hausdorff_px: f64,
    /// The rendered silhouette.
    pub rendered: Mask,
}

/// The final figures, computed once when the fit ends.
#[derive(Debug, Clone)]
struct Final {
    pose: Pose,
    views: Vec<ViewFigures>,
    judgement: Judgement,
    /// The pose's uncertainty, or why it could not be measured.
    uncertainty: std::result::Result<Uncertainty, String>,
    /// The camera corrections when asked for, or why they could not be estimated.
    corrections: Option<std::result::Result<Vec<CameraCorrection>, String>>,
    /// Whether they were applied.
    camera_test: Option<CameraTest>,
}

/// Search candidates scored per step.
const SEARCH_BATCH: usize = 16;
/// A candidate whose best loss has not improved for this many iterations is done.
const PATIENCE: usize = 25;

/// The step-wise pose estimator.
pub struct Estimator {
    /// The mesh (with its edge topology).
    model: RenderMesh,
    views: Vec<View>,
    windows: Vec<Window>,
    settings: FitSettings,
    centre: DVec3,
    radius: f64,
    phase: Phase,
    /// The mesh the search and the stages at or below its resolution render.
    search_model: RenderMesh,
    // Search state.
    rotations: Vec<DMat3>,
    next_rotation: usize,
    start: Pose,
    search: Option<Objective>,
    scored: Vec<Candidate>,
    // Refinement state.
    tracks: Vec<Track>,
    stage: usize,
    current: usize,
    iter_in_stage: usize,
    objective: Option<Objective>,
    iterations: usize,
    last_loss: f64,
    termination: Option<Termination>,
    done: Option<Final>,
    /// The views as given, once `views` holds the corrected cameras.
    input_views: Option<Vec<View>>,
}

impl Estimator {
    /// Sets up a fit of `mesh` to `views`. With `initial_pose`, the search is skipped.
    ///
    /// Errors: invalid settings or mesh, no views, or an object whose centre is
    /// behind a camera at the initial pose.
    pub fn new(mesh: Mesh, views: Vec<View>, initial_pose: Option<Pose>, settings: FitSettings) -> Result<Estimator> {
        settings.validate()?;
        if views.is_empty() {
            return Err(Error::Settings("at least one view is needed".into()));
        }
        mesh.validate("mesh")?;
        let b = mesh.bounds().ok_or_else(|| Error::Mesh {
            file: "mesh".into(),
            problem: "has no vertices".into(),
        })?;
        let windows = views.iter().map(|v| Window::for_view(v, settings.window)).collect();
        // Cells of about two pixels at the search resolution: silhouettes within a pixel.
        let search_model = RenderMesh::exact(mesh.clustered(settings.search.resolution * 3 / 8));
        let mut est = Estimator {
            centre: b.centre(),
            radius: (b.size().length() * 0.5).max(1e-12),
            search_model,
            model: RenderMesh::with_detail(mesh, settings.detail_px),
            views,
            windows,
            phase: Phase::Search,
            rotations: Vec::new(),
            next_rotation: 0,
            start: Pose::IDENTITY,
            search: None,
            scored: Vec::new(),
            tracks: Vec::new(),
            stage: 0,
            current: 0,
            iter_in_stage: 0,
            objective: None,
            iterations: 0,
            last_loss: f64::NAN,
            termination: None,
            done: None,
            input_views: None,
            settings,
        };
        match initial_pose {
            Some(p) => {
                p.validate()?;
                est.check_in_front(&p)?;
                est.begin_refine(vec![p])?;
            }
            None => {
                est.start = est.initial_guess()?;
                est.rotations = est.settings.search.sampling.rotations();
                let mut s = est.settings.clone();
                // The search only needs the targets' masks: no contour fields.
                s.lambda_contour = 0.0;
                s.lambda_iou = 1.0;
                est.search = Some(Objective::new(
                    &est.views,
                    &est.windows,
                    s.search.resolution,
                    s.objective(&s.stages[0]),
                )?);
            }
        }
        Ok(est)
    }

    /// The mesh being fitted.
    pub fn mesh(&self) -> &Mesh {
        &self.model.mesh
    }

    /// The views being fitted (once done with `refine_cameras`, with the corrected
    /// cameras).
    pub fn views(&self) -> &[View] {
        &self.views
    }

    /// The views as given (before any camera correction).
    pub fn input_views(&self) -> &[View] {
        self.input_views.as_deref().unwrap_or(&self.views)
    }

    /// Each view's window.
    pub fn windows(&self) -> &[Window] {
        &self.windows
    }

    /// The settings in use.
    pub fn settings(&self) -> &FitSettings {
        &self.settings
    }

    /// The phase and refinement stage the next step will work in.
    pub fn progress_phase(&self) -> (Phase, usize) {
        (self.phase, self.stage)
    }

    /// Whether the fit has finished.
    pub fn is_done(&self) -> bool {
        self.phase == Phase::Done
    }

    /// The starting scale: 1 (the CAD model is to scale) or from the masks' areas.
    fn initial_guess(&self) -> Result<Pose> {
        let mean_area = (init::surface_area(&self.model.mesh) / 4.0).max(1e-300);
        // One view: the depth at which a unit-scale object covers the mask's area.
        let depth = |v: &View| {
            let c = v.camera();
            (c.fx * c.fy * mean_area / v.known_area().max(1) as f64).sqrt()
        };
        let x = init::triangulate_centre(&self.views, depth)?;
        let s = match self.settings.scale_mode {
            ScaleMode::Fixed => 1.0,
            _ => init::scale_from_areas(&self.views, x, mean_area),
        };
        let scale = DVec3::splat(s);
        let pose = Pose {
            rotation: DMat3::IDENTITY,
            translation: x - scale * self.centre,
            scale,
        };
        self.check_in_front(&pose)?;
        Ok(pose)
    }

    /// An error naming the first view that sees the object's centre behind it.
    fn check_in_front(&self, pose: &Pose) -> Result<()> {
        let c = pose.apply(self.centre);
        for v in &self.views {
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

    fn begin_refine(&mut self, poses: Vec<Pose>) -> Result<()> {
        let n = self.views.len();
        self.tracks = poses.into_iter().map(|p| Track::new(p, n)).collect();
        self.phase = Phase::Refine;
        self.stage = 0;
        self.current = 0;
        self.iter_in_stage = 0;
        self.search = None;
        self.objective = Some(self.make_objective(0)?);
        Ok(())
    }

    fn make_objective(&self, stage: usize) -> Result<Objective> {
        let s = &self.settings.stages[stage];
        Objective::new(&self.views, &self.windows, s.resolution, self.settings.objective(s))
    }

    /// Does one unit of work and reports where the fit stands. To keep a step cheap,
    /// its `view_iou` is left empty: [`Estimator::progress`] fills it.
    ///
    /// Errors: none on validated inputs; an internal failure (a bug) is reported
    /// rather than hidden, and the estimator then stays where it was.
    pub fn step(&mut self) -> Result<Progress> {
        match self.phase {
            Phase::Search => self.search_step()?,
            Phase::Refine => self.refine_step()?,
            Phase::Done => {}
        }
        Ok(self.snapshot(Vec::new()))
    }

    /// The work the next step needs, to be computed by [`Shard`]s (other threads, Web
    /// Workers) and handed back with [`Estimator::respond`]; `None` when the fit is done.
    /// [`Estimator::step`] does the same work here.
    pub fn request(&self) -> Option<Request> {
        match self.phase {
            Phase::Search => Some(Request::Search {
                start: self.start,
                first: self.next_rotation,
                count: SEARCH_BATCH.min(self.rotations.len() - self.next_rotation),
            }),
            Phase::Refine => Some(Request::Evaluate {
                stage: self.stage,
                pose: self.tracks[self.current].pose,
                kind: self.refine_kind(),
                model_union: self
                    .objective
                    .as_ref()
                    .map(|o| o.model_union().to_vec())
                    .unwrap_or_default(),
            }),
            Phase::Done => None,
        }
    }

    /// Completes the step [`Estimator::request`] asked for, with the shards' responses
    /// to it (for an evaluation, together every view's part, once; for a search batch,
    /// every rotation of it).
    ///
    /// Errors: responses that do not answer the current request.
    pub fn respond(&mut self, responses: Vec<Response>) -> Result<Progress> {
        let bad = |m: String| Err(Error::Settings(format!("respond: {m}")));
        match (self.request(), self.phase) {
            (Some(Request::Search { first, count, .. }), Phase::Search) => {
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
            (Some(Request::Evaluate { .. }), Phase::Refine) => {
                let n = self.views.len();
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
            _ => return bad("the fit is done".into()),
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

    fn search_step(&mut self) -> Result<()> {
        let (first, count) = (
            self.next_rotation,
            SEARCH_BATCH.min(self.rotations.len() - self.next_rotation),
        );
        let targets = self.search.as_ref().map(|o| o.targets()).unwrap_or_default();
        let scored = score_rotations(
            &self.search_model.mesh,
            targets,
            &self.rotations[first..first + count],
            &self.start,
            self.centre,
            &self.settings,
        );
        self.finish_search_batch(scored)
    }

    /// Takes a batch of scored candidates (the next rotations in order); after the
    /// last batch, keeps the best and starts the refinement.
    fn finish_search_batch(&mut self, scored: Vec<Candidate>) -> Result<()> {
        self.next_rotation += scored.len();
        self.scored.extend(scored);
        if self.next_rotation >= self.rotations.len() {
            let best = search::select_best(
                std::mem::take(&mut self.scored),
                self.settings.search.keep,
                self.settings.search.min_separation_deg,
            );
            let poses: Vec<Pose> = best.iter().map(|c| c.pose).collect();
            let poses = if poses.is_empty() { vec![self.start] } else { poses };
            self.begin_refine(poses)?;
            if self.settings.robust {
                for (t, c) in self.tracks.iter_mut().zip(&best) {
                    t.weights = robust_weights(&c.ious.iter().map(|i| 1.0 - i).collect::<Vec<_>>());
                }
            }
        }
        Ok(())
    }

    /// The evaluation the next refinement iteration needs.
    fn refine_kind(&self) -> PartKind {
        match self.settings.optimiser {
            Optimiser::Adam => PartKind::Gradient,
            Optimiser::LevenbergMarquardt => PartKind::GaussNewton,
        }
    }

    fn refine_step(&mut self) -> Result<()> {
        let kind = self.refine_kind();
        let pose = self.tracks[self.current].pose;
        let weights = self.tracks[self.current].weights.clone();
        let model = if self.settings.stages[self.stage].resolution <= self.settings.search.resolution {
            &self.search_model
        } else {
            &self.model
        };
        let objective = self
            .objective
            .as_mut()
            .ok_or_else(|| Error::Settings("internal: no objective in the refine phase".into()))?;
        objective.set_weights(&weights)?;
        let union = objective.model_union().to_vec();
        let parts = objective.view_parts(model, &pose, kind, &union)?;
        self.refine_apply(&parts)
    }

    /// Completes a refinement iteration from every view's part at the current pose.
    fn refine_apply(&mut self, parts: &[ViewPart]) -> Result<()> {
        let stage = self.settings.stages[self.stage].clone();
        let last_stage = self.stage + 1 == self.settings.stages.len();
        let objective = self
            .objective
            .as_mut()
            .ok_or_else(|| Error::Settings("internal: no objective in the refine phase".into()))?;
        let t = &mut self.tracks[self.current];
        objective.set_weights(&t.weights)?;
        let (ev, ne) = objective.combine_parts(parts)?;
        let length = self.radius * t.pose.scale.max_element();
        let loss = match self.settings.optimiser {
            Optimiser::Adam => {
                let frac = self.iter_in_stage as f64 / stage.iterations.max(1) as f64;
                let lr = stage.lr_start * (stage.lr_end / stage.lr_start).powf(frac);
                let mut g = params::scale_gradient(&ev.gradient, length);
                match self.settings.scale_mode {
                    ScaleMode::Fixed => g[6..9].iter_mut().for_each(|v| *v = 0.0),
                    ScaleMode::Isotropic => params::isotropic_scale(&mut g),
                    ScaleMode::Anisotropic => {}
                }
                let d = t.adam.update(&g, &self.settings.adam, lr);
                t.record(ev.total);
                t.pose = params::apply(&t.pose, &d, length);
                ev.total
            }
            Optimiser::LevenbergMarquardt => {
                t.record(ev.total);
                let free = free_parameters(self.settings.scale_mode);
                let scaled = lm::scale_equations(&ne, length);
                t.pose = t.lm.next_pose(t.pose, scaled, free, |p, d| params::apply(p, d, length));
                ev.total
            }
        };
        self.iterations += 1;
        self.last_loss = loss;
        self.iter_in_stage += 1;
        // Convergence: the best loss improved by less than the tolerance over the
        // last 5 iterations (any stage; in the last one it ends the fit).
        let n = t.history.len();
        if self.iter_in_stage >= 6 && n > 5 {
            let old = t.history[..n - 5]
                .iter()
                .rev()
                .take(self.iter_in_stage - 5)
                .fold(f64::INFINITY, |a, &b| a.min(b));
            if old.is_finite() && old - t.best_loss <= self.settings.tolerance * old.abs().max(1e-12) {
                t.converged = last_stage;
                t.done_in_stage = true;
            }
        }
        if t.since_best >= PATIENCE || self.iter_in_stage >= stage.iterations {
            t.done_in_stage = true;
        }
        if t.done_in_stage {
            self.next_track()?;
        }
        Ok(())
    }

    fn next_track(&mut self) -> Result<()> {
        self.iter_in_stage = 0;
        if self.current + 1 < self.tracks.len() {
            self.current += 1;
            return Ok(());
        }
        // Stage finished for every track: keep the best ones, on to the next stage.
        let objective = self
            .objective
            .as_mut()
            .ok_or_else(|| Error::Settings("internal: no objective in the refine phase".into()))?;
        let mut scored: Vec<(f64, Track)> = std::mem::take(&mut self.tracks)
            .into_iter()
            .map(|mut t| {
                // Ranked by the mean over all views (not the candidate's own weights:
                // candidates must be compared on the same footing).
                t.pose = t.best_pose;
                let ious = objective.hard_ious(&self.model.mesh, &t.pose);
                (ious.iter().sum::<f64>() / ious.len().max(1) as f64, t)
            })
            .collect();
        scored.sort_by(|a, b| b.0.total_cmp(&a.0));
        let keep = self.settings.stages[self.stage].keep;
        self.tracks = scored.into_iter().take(keep).map(|(_, t)| t).collect();
        self.current = 0;
        if self.stage == 0 && self.settings.robust {
            let free = free_parameters(self.settings.scale_mode);
            for t in &mut self.tracks {
                if let Some((v, pose)) = leave_one_out(objective, &self.search_model, t, free, self.radius)? {
                    t.excluded[v] = true;
                    t.weights[v] = 0.0;
                    t.pose = pose;
                    t.best_pose = pose;
                }
            }
        }
        if self.stage + 1 < self.settings.stages.len() {
            self.stage += 1;
            for t in &mut self.tracks {
                t.adam = Adam::new();
                t.lm = Lm::new();
                t.best_loss = f64::INFINITY;
                t.since_best = 0;
                t.done_in_stage = false;
            }
            let mut objective = self.make_objective(self.stage)?;
            if self.settings.robust {
                for t in &mut self.tracks {
                    let ev = objective.value(&self.model, &t.pose)?;
                    let w = robust_weights(&ev.views.iter().map(|v| v.iou).collect::<Vec<_>>());
                    t.weights = w
                        .iter()
                        .zip(&t.excluded)
                        .map(|(w, &x)| if x { 0.0 } else { *w })
                        .collect();
                }
            }
            self.objective = Some(objective);
        } else {
            self.finish();
        }
        Ok(())
    }

    /// Ends the fit: the camera corrections when asked for, final figures at full
    /// resolution, the verdict, the uncertainty, the termination.
    fn finish(&mut self) {
        let mut pose = self.tracks[0].best_pose;
        let weights = self.tracks[0].weights.clone();
        let free = free_parameters(self.settings.scale_mode);
        let noise = NoiseModel::default();
        let mut corrections = None;
        let mut extra = None;
        let mut camera_test = None;
        if let Some(prior) = self.settings.refine_cameras {
            let last = self
                .settings
                .stages
                .last()
                .cloned()
                .expect("validated: at least one stage");
            let refined = fit_uncertainty(&self.model, &self.views, &self.windows, &pose, &weights, free, &noise)
                .and_then(|u| {
                    cameras::refine(
                        &self.model,
                        &self.views,
                        &self.windows,
                        &weights,
                        pose,
                        free,
                        last.resolution,
                        self.settings.objective(&last),
                        &prior,
                        &u.covariance,
                    )
                });
            match refined {
                Ok(r) => {
                    if r.test.applied {
                        pose = r.pose;
                        self.input_views = Some(std::mem::replace(&mut self.views, r.views));
                        self.tracks[0].best_pose = pose;
                        extra = Some(r.extra_covariance);
                    }
                    corrections = Some(Ok(r.corrections));
                    camera_test = Some(r.test);
                }
                Err(e) => corrections = Some(Err(e.to_string())),
            }
        }
        let t = &self.tracks[0];
        let views: Vec<ViewFigures> = self
            .views
            .iter()
            .map(|v| full_figures(&self.model.mesh, &pose, v))
            .collect();
        let names: Vec<&str> = self.views.iter().map(|v| v.name()).collect();
        let ious: Vec<f64> = views.iter().map(|f| f.iou).collect();
        let inconsistent: Vec<String> = self
            .views
            .iter()
            .zip(&t.weights)
            .filter(|(_, &w)| w < 0.5)
            .map(|(v, _)| v.name().to_string())
            .collect();
        let judgement = verdict::judge(&names, &ious, &inconsistent, &self.settings.verdict);
        self.termination = Some(if t.converged && judgement.verdict != Verdict::Failed {
            Termination::Converged
        } else if t.converged || t.since_best >= PATIENCE {
            Termination::Stalled
        } else {
            Termination::MaxIterations
        });
        let uncertainty = fit_uncertainty(&self.model, &self.views, &self.windows, &pose, &weights, free, &noise)
            .map(|mut u| {
                if let Some(x) = extra {
                    u.covariance += x;
                    u.std_dev = std_dev(&self.model.mesh, &pose, &u.covariance, u.std_dev.boundary_rms_px);
                }
                u
            })
            .map_err(|e| e.to_string());
        self.done = Some(Final {
            pose,
            views,
            judgement,
            uncertainty,
            corrections,
            camera_test,
        });
        self.objective = None;
        self.phase = Phase::Done;
    }

    /// Asks for (or stops asking for) the camera correction, with its prior, before the
    /// fit ends (`FitSettings::refine_cameras`).
    ///
    /// Errors: the fit is already done, or the prior is out of range.
    pub fn set_refine_cameras(&mut self, prior: Option<CameraPrior>) -> Result<()> {
        if self.done.is_some() {
            return Err(Error::Settings("camera correction: the fit is already done".into()));
        }
        if let Some(p) = &prior {
            p.validate()?;
        }
        self.settings.refine_cameras = prior;
        Ok(())
    }

    /// The views' camera corrections once done with `refine_cameras` (`Err` says why
    /// they could not be estimated); `None` otherwise.
    pub fn camera_corrections(&self) -> Option<std::result::Result<&[CameraCorrection], &str>> {
        self.done
            .as_ref()
            .and_then(|f| f.corrections.as_ref())
            .map(|c| c.as_ref().map(|v| v.as_slice()).map_err(|e| e.as_str()))
    }

    /// Once done with `refine_cameras`: how much of the loss the corrections removed
    /// and whether they were applied (`cameras` module doc "When to apply").
    pub fn camera_test(&self) -> Option<CameraTest> {
        self.done.as_ref().and_then(|f| f.camera_test)
    }

    /// The pose the fit currently holds (the best so far once done).
    pub fn pose(&self) -> Pose {
        match self.phase {
            Phase::Search => self
                .scored
                .iter()
                .max_by(|a, b| a.score.total_cmp(&b.score))
                .map_or(self.start, |c| c.pose),
            Phase::Refine => self.tracks[self.current].pose,
            Phase::Done => self.tracks[0].best_pose,
        }
    }

    /// A snapshot of the state, with the hard IoU of every view at the current
    /// stage's resolution (the search's during the search; full resolution once done).
    pub fn progress(&self) -> Progress {
        let pose = self.pose();
        let view_iou = if let Some(f) = &self.done {
            f.views.iter().map(|v| v.iou).collect()
        } else {
            let (objective, mesh) = match (&self.search, &self.objective) {
                (Some(s), _) => (s, &self.search_model.mesh),
                (None, Some(o)) => (o, &self.model.mesh),
                (None, None) => return self.snapshot(Vec::new()),
            };
            let mut bits = BitMask::empty(0, 0);
            objective
                .targets()
                .iter()
                .map(|t| {
                    let proj = crate::raster::project::project_mesh(mesh, &pose, &t.camera);
                    hard::render_bits_into(&proj, &mesh.triangles, &t.camera, &mut bits);
                    t.hard_iou(&bits)
                })
                .collect()
        };
        self.snapshot(view_iou)
    }

    fn snapshot(&self, view_iou: Vec<f64>) -> Progress {
        Progress {
            phase: self.phase,
            iteration: self.iterations,
            searched: self.next_rotation,
            search_total: self.rotations.len(),
            stage: self.stage,
            candidate: self.current,
            loss: self.last_loss,
            view_iou,
            pose: self.pose(),
            termination: self.termination,
            verdict: self.done.as_ref().map(|f| f.judgement.verdict),
        }
    }

    /// The loss history of the winning candidate (all stages), once done; of the
    /// current candidate before.
    pub fn loss_history(&self) -> Vec<f64> {
        self.tracks
            .get(self.current)
            .map(|t| t.history.clone())
            .unwrap_or_default()
    }

    /// The verdict and the views it doubts, once done.
    pub fn judgement(&self) -> Option<&Judgement> {
        self.done.as_ref().map(|f| &f.judgement)
    }

    /// Candidate cameras ranked by how much a photograph from there is predicted to
    /// shrink the final pose's uncertainty, best first (`candidates`, or 64 viewpoints
    /// on a sphere around the object: `crate::uncertainty::next_view`).
    ///
    /// Errors: the fit is not done, or its uncertainty could not be measured.
    pub fn suggest_views(&self, candidates: Option<&[crate::camera::Camera]>) -> Result<Vec<RankedView>> {
        let Some(f) = &self.done else {
            return Err(Error::Settings("next view: the fit is not done".into()));
        };
        let u = f
            .uncertainty
            .as_ref()
            .map_err(|e| Error::Settings(format!("next view: no uncertainty: {e}")))?;
        let sphere;
        let candidates = match candidates {
            Some(c) => c,
            None => {
                sphere = sphere_candidates(&self.model, &self.views, &f.pose, next_view::SPHERE)?;
                &sphere
            }
        };
        rank_views(&self.model, &f.pose, u, candidates, &NoiseModel::default())
    }

    /// `count` candidate viewpoints over `shell` around the finished fit's pose
    /// ([`crate::uncertainty::candidate_viewpoints`]), for [`Estimator::suggest_views`].
    ///
    /// Errors: the fit is not done.
    pub fn viewpoints(&self, count: usize, shell: Viewpoints) -> Result<Vec<crate::camera::Camera>> {
        let Some(f) = &self.done else {
            return Err(Error::Settings("next view: the fit is not done".into()));
        };
        candidate_viewpoints(&self.model, &self.views, &f.pose, count, shell)
    }

    /// The parameters the fit frees (its scale mode).
    pub fn free(&self) -> lm::Free {
        free_parameters(self.settings.scale_mode)
    }

    /// The final pose's uncertainty once done (`Err` says why it could not be
    /// measured); `None` before.
    pub fn uncertainty(&self) -> Option<std::result::Result<&Uncertainty, &str>> {
        self.done
            .as_ref()
            .map(|f| f.uncertainty.as_ref().map_err(|e| e.as_str()))
    }

    /// Per-view figures at full resolution for a pose (cached for the final pose).
    pub fn view_figures(&self, pose: &Pose) -> Vec<ViewFigures> {
        match &self.done {
            Some(f) if f.pose == *pose => f.views.clone(),
            _ => self
                .views
                .iter()
                .map(|v| full_figures(&self.model.mesh, pose, v))
                .collect(),
        }
    }
}

/// A view's figures at full resolution (IoU over the known pixels).
fn full_figures(mesh: &Mesh, pose: &Pose, view: &View) -> ViewFigures {
    let rendered = hard::render(mesh, pose, view.camera());
    ViewFigures {
        iou: metrics::hard_iou_known(&rendered, view.mask(), view.ignore()),
        hausdorff_px: metrics::hausdorff_px(&rendered, view.mask()),
        rendered,
    }
}
