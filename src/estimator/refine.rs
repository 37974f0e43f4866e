//! The refinement (SPEC §4 step 4): the kept candidates ("tracks") refined stage by
//! stage, coarse to fine — each iteration one evaluation of the stage's objective and
//! one optimiser step — then ranked, the best kept for the next stage; after the
//! first stage, the leave-one-out consensus test and the views' robust weights.
//!
//! Rivals: at a stage's end, besides the `keep` best, up to [`RIVALS`] candidates go on
//! that are distinct from every one kept (ADD ≥ [`DISTINCT_ADD`] of the diameter, up to
//! the object's symmetries) and score within [`RIVAL_GAP`] of the best. Each stage
//! re-ranks them with the others on the same footing — the last at full detail — so a
//! pose that won the coarse search by a hair can still lose to its flipped twin; what
//! is left of them at the end is what [`finish`](super::finish) weighs as
//! alternatives. When the masks tell the poses apart early, no rival passes the gap and
//! the refinement costs what it did.

use super::robust::{leave_one_out, robust_weights};
use super::setup::FitSetup;
use super::shard::{Request, Worker};
use super::{Estimator, State};
use crate::error::{Error, Result};
use crate::loss::objective::{PartKind, ViewPart};
use crate::optim::adam::Adam;
use crate::optim::lm::Lm;
use crate::optim::params;
use crate::optim::schedule::Optimiser;
use crate::pose::Pose;

/// A candidate whose best loss has not improved for this many iterations is done.
pub(super) const PATIENCE: usize = 25;

/// At most this many rivals go on beside a stage's `keep` best (module doc).
pub(super) const RIVALS: usize = 2;

/// A rival's mean hard IoU at the stage's resolution is at most this far below the
/// best's.
pub(super) const RIVAL_GAP: f64 = 0.08;

/// Two poses are distinct when their ADD (up to the object's symmetries) is at least
/// this fraction of the diameter: the usual line between a right and a wrong pose.
pub(crate) const DISTINCT_ADD: f64 = 0.1;

/// One candidate being refined.
#[derive(Debug, Clone)]
pub(super) struct Track {
    pub pose: Pose,
    adam: Adam,
    lm: Lm<Pose>,
    pub best_pose: Pose,
    pub best_loss: f64,
    pub since_best: usize,
    pub history: Vec<f64>,
    done_in_stage: bool,
    pub converged: bool,
    /// The views' weights in this candidate's objective (robust re-weighting).
    pub weights: Vec<f64>,
    /// Views the leave-one-out test found to contradict the others (weight 0).
    pub excluded: Vec<bool>,
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

    /// A new stage: fresh optimiser state, from the best pose so far.
    fn restart(&mut self) {
        self.adam = Adam::new();
        self.lm = Lm::new();
        self.best_loss = f64::INFINITY;
        self.since_best = 0;
        self.done_in_stage = false;
    }
}

/// The refinement's state.
pub(super) struct Refinement {
    pub tracks: Vec<Track>,
    pub stage: usize,
    /// The track the next iteration refines.
    pub current: usize,
    iter_in_stage: usize,
}

impl Refinement {
    /// The evaluation the next iteration needs.
    pub fn request(&self, setup: &FitSetup, local: &Worker) -> Request {
        Request::Evaluate {
            stage: self.stage,
            pose: self.tracks[self.current].pose,
            kind: match setup.settings.optimiser {
                Optimiser::Adam => PartKind::Gradient,
                Optimiser::LevenbergMarquardt => PartKind::GaussNewton,
            },
            model_union: local.stage_union(self.stage).unwrap_or_default(),
        }
    }
}

impl Estimator {
    /// Starts refining `poses`; `losses` are each one's per-view losses from the search
    /// (the robust weights' start).
    pub(super) fn begin_refine(&mut self, poses: Vec<Pose>, losses: Option<Vec<Vec<f64>>>) -> Result<()> {
        let n = self.setup.views.len();
        let mut tracks: Vec<Track> = poses.into_iter().map(|p| Track::new(p, n)).collect();
        if let (true, Some(losses)) = (self.setup.settings.robust, losses) {
            for (t, l) in tracks.iter_mut().zip(&losses) {
                t.weights = robust_weights(l);
            }
        }
        self.local.stage_objective(&self.setup, 0)?;
        self.state = State::Refine(Refinement {
            tracks,
            stage: 0,
            current: 0,
            iter_in_stage: 0,
        });
        Ok(())
    }

    /// Completes a refinement iteration from every view's part at the current pose.
    pub(super) fn refine_apply(&mut self, parts: &[ViewPart]) -> Result<()> {
        let State::Refine(r) = &mut self.state else {
            return Err(Error::Settings("internal: an evaluation outside the refinement".into()));
        };
        let settings = &self.setup.settings;
        let stage = &settings.stages[r.stage];
        let last_stage = r.stage + 1 == settings.stages.len();
        let objective = self.local.stage_objective(&self.setup, r.stage)?;
        let t = &mut r.tracks[r.current];
        objective.set_weights(&t.weights)?;
        let (ev, ne) = objective.combine_parts(parts)?;
        let length = self.setup.length(&t.pose);
        t.record(ev.total);
        match settings.optimiser {
            Optimiser::Adam => {
                let frac = r.iter_in_stage as f64 / stage.iterations.max(1) as f64;
                let lr = stage.lr_start * (stage.lr_end / stage.lr_start).powf(frac);
                let mut g = params::scale_gradient(&ev.gradient, length);
                settings.scale_mode.restrict(&mut g);
                let d = t.adam.update(&g, &settings.adam, lr);
                t.pose = params::apply(&t.pose, &d, length);
            }
            Optimiser::LevenbergMarquardt => {
                t.pose = t.lm.next_pose(t.pose, &ne, settings.scale_mode, length);
                if t.lm.stalled() {
                    t.converged = last_stage;
                    t.done_in_stage = true;
                }
            }
        }
        self.iterations += 1;
        self.last_loss = ev.total;
        r.iter_in_stage += 1;
        // Convergence: the best loss improved by less than the tolerance over the
        // last 5 iterations (any stage; in the last one it ends the fit).
        let n = t.history.len();
        if r.iter_in_stage >= 6 && n > 5 {
            let old = t.history[..n - 5]
                .iter()
                .rev()
                .take(r.iter_in_stage - 5)
                .fold(f64::INFINITY, |a, &b| a.min(b));
            if old.is_finite() && old - t.best_loss <= settings.tolerance * old.abs().max(1e-12) {
                t.converged = last_stage;
                t.done_in_stage = true;
            }
        }
        if t.since_best >= PATIENCE || r.iter_in_stage >= stage.iterations {
            t.done_in_stage = true;
        }
        if t.done_in_stage {
            self.next_track()?;
        }
        Ok(())
    }

    /// On to the next track, or, when every track has finished the stage, to the next
    /// stage with the best of them (or to the end).
    fn next_track(&mut self) -> Result<()> {
        let State::Refine(r) = &mut self.state else {
            return Err(Error::Settings("internal: no refinement".into()));
        };
        r.iter_in_stage = 0;
        if r.current + 1 < r.tracks.len() {
            r.current += 1;
            return Ok(());
        }
        let settings = &self.setup.settings;
        let objective = self.local.stage_objective(&self.setup, r.stage)?;
        // Ranked by the mean hard IoU over all views (not the candidate's own weights:
        // candidates must be compared on the same footing).
        let mut scored: Vec<(f64, Track)> = std::mem::take(&mut r.tracks)
            .into_iter()
            .map(|mut t| {
                t.pose = t.best_pose;
                let ious = objective.hard_ious(self.setup.mesh(), &t.pose);
                (ious.iter().sum::<f64>() / ious.len().max(1) as f64, t)
            })
            .collect();
        scored.sort_by(|a, b| b.0.total_cmp(&a.0));
        let keep = settings.stages[r.stage].keep;
        let best = scored.first().map_or(0.0, |s| s.0);
        let mut kept: Vec<Track> = Vec::new();
        let mut rivals = 0;
        for (score, t) in scored {
            if kept.len() < keep {
                kept.push(t);
            } else if rivals < RIVALS
                && score >= best - RIVAL_GAP
                && kept
                    .iter()
                    .all(|k| self.setup.separation(&k.pose, &t.pose).add_rel >= DISTINCT_ADD)
            {
                kept.push(t);
                rivals += 1;
            }
        }
        r.tracks = kept;
        r.current = 0;
        if r.stage == 0 && settings.robust {
            for t in &mut r.tracks {
                let found = leave_one_out(
                    objective,
                    &self.setup.search_model,
                    t,
                    settings.scale_mode,
                    self.setup.radius,
                )?;
                if let Some((v, pose)) = found {
                    t.excluded[v] = true;
                    t.weights[v] = 0.0;
                    t.pose = pose;
                    t.best_pose = pose;
                }
            }
        }
        if r.stage + 1 == settings.stages.len() {
            let mut tracks = std::mem::take(&mut r.tracks);
            let winner = tracks.remove(0);
            let done = self.finish(winner, tracks);
            self.state = State::Done(Box::new(done));
            return Ok(());
        }
        r.stage += 1;
        r.tracks.iter_mut().for_each(Track::restart);
        let objective = self.local.stage_objective(&self.setup, r.stage)?;
        if settings.robust {
            for t in &mut r.tracks {
                let ev = objective.value(&self.setup.model, &t.pose)?;
                let w = robust_weights(&ev.views.iter().map(|v| v.iou).collect::<Vec<_>>());
                t.weights = w
                    .iter()
                    .zip(&t.excluded)
                    .map(|(w, &x)| if x { 0.0 } else { *w })
                    .collect();
            }
        }
        Ok(())
    }

    /// The loss history of the winning candidate (all stages), once done; of the
    /// current candidate before.
    pub fn loss_history(&self) -> Vec<f64> {
        match &self.state {
            State::Search { .. } => Vec::new(),
            State::Refine(r) => r.tracks[r.current].history.clone(),
            State::Done(f) => f.track.history.clone(),
        }
    }
}
