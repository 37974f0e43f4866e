//! The pipeline as a step-wise object (SPEC §4): initialise, search orientations,
//! refine the best candidates coarse-to-fine, report. [`Estimator::step`] does one
//! small unit of work (a batch of search candidates or one optimiser iteration) so
//! that a UI can show every iteration; the state keeps the best pose so far.
//! The same object drives the command line and the browser.

use crate::error::{Error, Result};
use crate::mask::Mask;
use crate::mesh::Mesh;
use crate::metrics;
use crate::optim::adam::{Adam, AdamSettings};
use crate::optim::lm::{self, Free, Lm};
use crate::optim::search::{self, Candidate, LowResView, SearchSettings};
use crate::optim::{init, params};
use crate::pose::Pose;
use crate::raster::hard;
use crate::refine::{Optimiser, RefineTarget, StageSettings};
use crate::view::View;
use glam::{DMat3, DVec3};
use serde::{Deserialize, Serialize};

/// How the scale is fitted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ScaleMode {
    /// Per-axis scale (9-DoF; the default).
    Anisotropic,
    /// One scale for all axes (7-DoF).
    Isotropic,
    /// The CAD model is to scale: the scale stays at the initial value (1 unless given).
    Fixed,
}

/// Everything the fit can be told.
#[derive(Debug, Clone)]
pub struct FitSettings {
    /// The coarse orientation search.
    pub search: SearchSettings,
    /// The coarse-to-fine refinement stages, in order.
    pub stages: Vec<StageSettings>,
    /// Adam's step sizes (multiplied by each stage's factor).
    pub adam: AdamSettings,
    /// Loss weight of the soft IoU term, λ1 (default 1).
    pub lambda_iou: f64,
    /// Loss weight of the contour (Hausdorff) term, λ2 (default 0.1, applied in the stages that enable it).
    pub lambda_contour: f64,
    /// How the scale is fitted.
    pub scale_mode: ScaleMode,
    /// A stage ends for a candidate when its best loss improved by less than this
    /// (relative) over 5 iterations (default 1e-3); in the last stage that is convergence.
    pub tolerance: f64,
}

impl Default for FitSettings {
    fn default() -> Self {
        FitSettings {
            search: SearchSettings::default(),
            stages: StageSettings::default_schedule(),
            adam: AdamSettings::default(),
            lambda_iou: 1.0,
            lambda_contour: 0.1,
            scale_mode: ScaleMode::Anisotropic,
            tolerance: 1e-3,
        }
    }
}

impl FitSettings {
    /// Checks ranges.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::Settings(m));
        if self.stages.is_empty() {
            return bad("at least one refinement stage is needed".into());
        }
        for (i, s) in self.stages.iter().enumerate() {
            if !(s.sigma > 0.0 && s.sigma.is_finite()) || s.resolution < 8 || s.keep == 0 {
                return bad(format!("stage {i}: sigma must be > 0, resolution ≥ 8 and keep ≥ 1"));
            }
        }
        if self.search.keep == 0 || self.search.resolution < 8 {
            return bad("search: keep ≥ 1 and resolution ≥ 8".into());
        }
        if !(self.lambda_iou >= 0.0 && self.lambda_contour >= 0.0) || self.lambda_iou + self.lambda_contour == 0.0 {
            return bad("λ1 and λ2 must be ≥ 0 and not both 0".into());
        }
        Ok(())
    }
}

/// What the estimator is doing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Phase {
    /// Scoring candidate orientations.
    Search,
    /// Gradient refinement of the best candidates.
    Refine,
    /// Finished.
    Done,
}

/// Why the fit stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Termination {
    /// The loss stopped improving by more than the tolerance.
    Converged,
    /// The last stage ran all its iterations.
    MaxIterations,
    /// The loss rose or stayed flat for long: the best pose so far was kept.
    Stalled,
}

/// A snapshot after a step, for display.
#[derive(Debug, Clone, Serialize)]
pub struct Progress {
    /// Current phase.
    pub phase: Phase,
    /// Optimiser iterations done so far (all candidates, all stages).
    pub iteration: usize,
    /// Search candidates scored so far / in all.
    pub searched: usize,
    /// Number of search candidates in all.
    pub search_total: usize,
    /// Refinement stage (0-based) and candidate being refined.
    pub stage: usize,
    /// Candidate index being refined.
    pub candidate: usize,
    /// The loss at the current pose (NaN during search).
    pub loss: f64,
    /// Hard IoU per view at the current pose, at the current stage's resolution.
    pub view_iou: Vec<f64>,
    /// The current pose.
    #[serde(skip)]
    pub pose: Pose,
    /// Why the fit stopped, once done.
    pub termination: Option<Termination>,
}

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
}

impl Track {
    fn new(pose: Pose) -> Track {
        Track {
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
}

/// The step-wise pose estimator.
pub struct Estimator {
    mesh: Mesh,
    views: Vec<View>,
    settings: FitSettings,
    centre: DVec3,
    radius: f64,
    phase: Phase,
    // Search state.
    search_mesh: Mesh,
    rotations: Vec<DMat3>,
    next_rotation: usize,
    start: Pose,
    low: Vec<LowResView>,
    scored: Vec<Candidate>,
    // Refinement state.
    tracks: Vec<Track>,
    stage: usize,
    current: usize,
    iter_in_stage: usize,
    target: Option<RefineTarget>,
    iterations: usize,
    last_loss: f64,
    termination: Option<Termination>,
}

/// Appends a loss to a track's history and keeps its best pose.
fn record(t: &mut Track, loss: f64) {
    t.history.push(loss);
    if loss < t.best_loss {
        t.best_loss = loss;
        t.best_pose = t.pose;
        t.since_best = 0;
    } else {
        t.since_best += 1;
    }
}

/// Search candidates scored per step.
const SEARCH_BATCH: usize = 16;

impl Estimator {
    /// Sets up a fit of `mesh` to `views`. With `initial_pose`, the search is skipped.
    pub fn new(mesh: Mesh, views: Vec<View>, initial_pose: Option<Pose>, settings: FitSettings) -> Result<Estimator> {
        settings.validate()?;
        if views.is_empty() {
            return Err(Error::Settings("at least one view is needed".into()));
        }
        mesh.validate("mesh")?;
        for v in &views {
            crate::io::scene::check_mask(&v.name, "mask", &v.mask, v.camera.width, v.camera.height)?;
        }
        let b = mesh.bounds().ok_or_else(|| Error::Mesh {
            file: "mesh".into(),
            problem: "has no vertices".into(),
        })?;
        let centre = b.centre();
        let radius = (b.size().length() * 0.5).max(1e-12);
        let mut est = Estimator {
            low: Vec::new(),
            search_mesh: Mesh::default(),
            rotations: Vec::new(),
            next_rotation: 0,
            start: Pose::IDENTITY,
            scored: Vec::new(),
            tracks: Vec::new(),
            stage: 0,
            current: 0,
            iter_in_stage: 0,
            target: None,
            iterations: 0,
            last_loss: f64::NAN,
            termination: None,
            phase: Phase::Search,
            mesh,
            views,
            settings,
            centre,
            radius,
        };
        // Cells of about two pixels at the search resolution: silhouettes within a pixel.
        // The search and the refinement stages at that resolution or below use it.
        est.search_mesh = est.mesh.clustered(est.settings.search.resolution * 3 / 8);
        match initial_pose {
            Some(p) => {
                p.validate()?;
                est.check_in_front(&p)?;
                est.begin_refine(vec![p])?;
            }
            None => {
                est.start = est.initial_guess()?;
                est.rotations = est.settings.search.sampling.rotations();
                est.low = search::low_res_views(&est.views, est.settings.search.resolution);
            }
        }
        Ok(est)
    }

    /// The mesh being fitted.
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// The views being fitted.
    pub fn views(&self) -> &[View] {
        &self.views
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

    /// Centre and isotropic scale from the masks (SPEC §4 step 2), identity rotation.
    fn initial_guess(&self) -> Result<Pose> {
        let mean_area = (init::surface_area(&self.mesh) / 4.0).max(1e-300);
        // One view: the depth at which a unit-scale object covers the mask's area.
        let depth = |v: &View| (v.camera.fx * v.camera.fy * mean_area / v.mask.area().max(1) as f64).sqrt();
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
            if v.camera.to_camera(c).z <= 0.0 {
                return Err(Error::View {
                    view: v.name.clone(),
                    problem: "the object's centre is behind this camera (check the camera's extrinsics and convention)"
                        .into(),
                });
            }
        }
        Ok(())
    }

    fn begin_refine(&mut self, poses: Vec<Pose>) -> Result<()> {
        self.tracks = poses.into_iter().map(Track::new).collect();
        self.phase = Phase::Refine;
        self.stage = 0;
        self.current = 0;
        self.iter_in_stage = 0;
        self.target = Some(self.make_target(0));
        Ok(())
    }

    fn make_target(&self, stage: usize) -> RefineTarget {
        let s = &self.settings.stages[stage];
        RefineTarget::new(&self.views, s, self.settings.lambda_iou, self.settings.lambda_contour)
    }

    /// Does one unit of work and reports where the fit stands. To keep a step cheap,
    /// its `view_iou` is left empty: [`Estimator::progress`] fills it.
    pub fn step(&mut self) -> Progress {
        match self.phase {
            Phase::Search => self.search_step(),
            Phase::Refine => self.refine_step(),
            Phase::Done => {}
        }
        self.snapshot(Vec::new())
    }

    /// Steps until done (at most `max_steps`); returns the last progress.
    pub fn run(&mut self, max_steps: usize) -> Progress {
        for _ in 0..max_steps {
            if self.is_done() {
                break;
            }
            self.step();
        }
        self.progress()
    }

    fn search_step(&mut self) {
        let end = (self.next_rotation + SEARCH_BATCH).min(self.rotations.len());
        for i in self.next_rotation..end {
            let r = self.rotations[i];
            let s = self.start.scale;
            let c = self.start.apply(self.centre);
            let pose = Pose {
                rotation: r,
                translation: c - r * (s * self.centre),
                scale: s,
            };
            let cand = search::score_candidate(
                &self.search_mesh,
                &self.low,
                pose,
                self.centre,
                self.settings.search.refit_rounds,
            );
            self.scored.push(cand);
        }
        self.next_rotation = end;
        if self.next_rotation >= self.rotations.len() {
            let best = search::select_best(
                std::mem::take(&mut self.scored),
                self.settings.search.keep,
                self.settings.search.min_separation_deg,
            );
            let poses: Vec<Pose> = best.iter().map(|c| c.pose).collect();
            let poses = if poses.is_empty() { vec![self.start] } else { poses };
            // begin_refine cannot fail here: the poses came from valid cameras and masks.
            let _ = self.begin_refine(poses);
        }
    }

    fn refine_step(&mut self) {
        let stage = self.settings.stages[self.stage].clone();
        let last_stage = self.stage + 1 == self.settings.stages.len();
        let target = self
            .target
            .as_mut()
            .expect("a refinement target exists in the refine phase");
        let mesh = if stage.resolution <= self.settings.search.resolution {
            &self.search_mesh
        } else {
            &self.mesh
        };
        let t = &mut self.tracks[self.current];
        let length = self.radius * t.pose.scale.max_element();
        let loss = match stage.optimiser {
            Optimiser::Adam => {
                let (loss, grad) = target.loss_and_gradient(mesh, &t.pose);
                let frac = self.iter_in_stage as f64 / stage.iterations.max(1) as f64;
                let lr = stage.lr_start * (stage.lr_end / stage.lr_start).powf(frac);
                let mut g = params::scale_gradient(&grad, length);
                match self.settings.scale_mode {
                    ScaleMode::Fixed => g[6..9].iter_mut().for_each(|v| *v = 0.0),
                    ScaleMode::Isotropic => params::isotropic_scale(&mut g),
                    ScaleMode::Anisotropic => {}
                }
                let d = t.adam.update(&g, &self.settings.adam, lr);
                record(t, loss);
                t.pose = params::apply(&t.pose, &d, length);
                loss
            }
            Optimiser::LevenbergMarquardt => {
                let ne = target.normal_equations(mesh, &t.pose);
                let loss = 2.0 * ne.cost;
                record(t, loss);
                let free = match self.settings.scale_mode {
                    ScaleMode::Fixed => Free::NoScale,
                    ScaleMode::Isotropic => Free::IsotropicScale,
                    ScaleMode::Anisotropic => Free::All,
                };
                let scaled = lm::scale_equations(&ne, length);
                t.pose = t.lm.next_pose(t.pose, scaled, free, |p, d| params::apply(p, d, length));
                loss
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
        if t.since_best >= 25 {
            t.done_in_stage = true;
        }
        if self.iter_in_stage >= stage.iterations {
            t.done_in_stage = true;
        }
        if t.done_in_stage {
            self.next_track();
        }
    }

    fn next_track(&mut self) {
        self.iter_in_stage = 0;
        if self.current + 1 < self.tracks.len() {
            self.current += 1;
            return;
        }
        // Stage finished for every track: keep the best ones, on to the next stage.
        let target = self.target.as_ref().expect("target exists");
        let mut scored: Vec<(f64, Track)> = std::mem::take(&mut self.tracks)
            .into_iter()
            .map(|mut t| {
                t.pose = t.best_pose;
                (target.hard_score(&self.mesh, &t.pose), t)
            })
            .collect();
        scored.sort_by(|a, b| b.0.total_cmp(&a.0));
        let keep = self.settings.stages[self.stage].keep;
        self.tracks = scored.into_iter().take(keep).map(|(_, t)| t).collect();
        if self.stage + 1 < self.settings.stages.len() {
            self.stage += 1;
            self.current = 0;
            for t in &mut self.tracks {
                t.adam = Adam::new();
                t.lm = Lm::new();
                t.best_loss = f64::INFINITY;
                t.since_best = 0;
                t.done_in_stage = false;
            }
            self.target = Some(self.make_target(self.stage));
        } else {
            let t = &self.tracks[0];
            self.termination = Some(if t.converged {
                Termination::Converged
            } else if t.since_best >= 25 {
                Termination::Stalled
            } else {
                Termination::MaxIterations
            });
            self.current = 0;
            self.phase = Phase::Done;
        }
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
    /// stage's resolution (the search's 64 px during the search).
    pub fn progress(&self) -> Progress {
        let pose = self.pose();
        let view_iou = match (&self.phase, &self.target) {
            (Phase::Search, _) | (_, None) => self
                .low
                .iter()
                .map(|v| {
                    let proj = crate::raster::project::project_mesh(&self.search_mesh, &pose, &v.camera);
                    hard::render_bits(&proj, &self.search_mesh.triangles, &v.camera).iou(&v.bits)
                })
                .collect(),
            (_, Some(t)) => t.hard_ious(&self.mesh, &pose),
        };
        self.snapshot(view_iou)
    }

    fn snapshot(&self, view_iou: Vec<f64>) -> Progress {
        let pose = self.pose();
        Progress {
            phase: self.phase,
            iteration: self.iterations,
            searched: self.next_rotation,
            search_total: self.rotations.len(),
            stage: self.stage,
            candidate: self.current,
            loss: self.last_loss,
            view_iou,
            pose,
            termination: self.termination,
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

    /// Per-view figures at full resolution for a pose: (hard IoU, Hausdorff px, rendered mask).
    pub fn view_figures(&self, pose: &Pose) -> Vec<(f64, f64, Mask)> {
        self.views
            .iter()
            .map(|v| {
                let m = hard::render(&self.mesh, pose, &v.camera);
                (metrics::hard_iou(&m, &v.mask), metrics::hausdorff_px(&m, &v.mask), m)
            })
            .collect()
    }
}
