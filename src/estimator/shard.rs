//! The one step path. Every step of a fit is a [`Request`] (a search batch, or every
//! view's part of a refinement iteration) answered by [`Response`]s and completed by
//! [`Estimator::respond`](super::Estimator::respond). [`Estimator::step`](super::Estimator::step)
//! answers its own request with a [`Worker`] holding every view; a [`Shard`] — the same
//! worker over some of the views, with its own [`FitSetup`], in another thread or Web
//! Worker — answers a share of it. Both run [`Worker::work`], so a pool's fit is the
//! single worker's, bit for bit, by construction.

use super::setup::FitSetup;
use crate::error::{Error, Result};
use crate::loss::objective::{Objective, PartKind, ViewPart};
use crate::mesh::Mesh;
use crate::optim::search::{self, Candidate};
use crate::pose::Pose;
use crate::raster::hard::BitMask;
use crate::view::View;
use crate::window::Window;
use glam::DMat3;

/// Work one estimator step needs (see the module doc).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Request {
    /// Score the search's rotations `first..first + count` from the start pose `start`.
    Search {
        /// The start pose (centre and scale of every candidate).
        start: Pose,
        /// First rotation.
        first: usize,
        /// Number of rotations.
        count: usize,
    },
    /// Every view's part of refinement stage `stage`'s objective at `pose`.
    Evaluate {
        /// The stage.
        stage: usize,
        /// The pose.
        pose: Pose,
        /// What to compute.
        kind: PartKind,
        /// Each view's union for the Gauss–Newton model (all views, in order).
        model_union: Vec<f64>,
    },
}

impl Request {
    /// The request split for `n` workers: a search batch into `n` contiguous ranges
    /// (fewer when it is small); an evaluation unchanged for each (every shard computes
    /// its own views).
    pub fn split(&self, n: usize) -> Vec<Request> {
        let n = n.max(1);
        match self {
            Request::Search { start, first, count } => {
                let per = count.div_ceil(n).max(1);
                (0..*count)
                    .step_by(per)
                    .map(|k| Request::Search {
                        start: *start,
                        first: first + k,
                        count: per.min(count - k),
                    })
                    .collect()
            }
            r @ Request::Evaluate { .. } => vec![r.clone(); n],
        }
    }
}

/// A worker's answer to a [`Request`].
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Response {
    /// Scored search candidates for rotations `first..first + candidates.len()`.
    Candidates {
        /// First rotation.
        first: usize,
        /// The candidates, in rotation order.
        candidates: Vec<Candidate>,
    },
    /// The parts of views `views` (estimator view indices), in that order.
    Parts {
        /// The views.
        views: Vec<usize>,
        /// Their parts.
        parts: Vec<ViewPart>,
    },
}

/// The objectives a worker keeps between requests: the search's (over every view: a
/// candidate is scored over all of them) and the current stage's (over its views).
pub(crate) struct Worker {
    mine: Vec<usize>,
    search: Option<Objective>,
    stage: Option<(usize, Objective)>,
}

impl Worker {
    /// A worker computing the parts of views `mine`.
    pub(crate) fn new(mine: Vec<usize>) -> Worker {
        Worker {
            mine,
            search: None,
            stage: None,
        }
    }

    /// The search's objective: hard IoUs only (no contour fields).
    pub(crate) fn search_objective(&mut self, setup: &FitSetup) -> Result<&mut Objective> {
        if self.search.is_none() {
            let mut s = setup.settings.clone();
            s.lambda_contour = 0.0;
            s.lambda_region = 0.0;
            s.lambda_iou = 1.0;
            let o = Objective::new(
                &setup.views,
                &setup.windows,
                s.search.resolution,
                s.objective(&s.stages[0]),
            )?;
            self.search = Some(o);
        }
        Ok(self.search.as_mut().expect("set above"))
    }

    /// Stage `stage`'s objective over this worker's views (the previous stage's is
    /// dropped).
    ///
    /// Errors: no such stage.
    pub(crate) fn stage_objective(&mut self, setup: &FitSetup, stage: usize) -> Result<&mut Objective> {
        let s = setup
            .settings
            .stages
            .get(stage)
            .ok_or_else(|| Error::Settings(format!("no stage {stage}")))?;
        if self.stage.as_ref().is_none_or(|(k, _)| *k != stage) {
            self.stage = None;
            let views: Vec<View> = self.mine.iter().map(|&v| setup.views[v].clone()).collect();
            let windows: Vec<Window> = self.mine.iter().map(|&v| setup.windows[v]).collect();
            let o = Objective::new(&views, &windows, s.resolution, setup.settings.stage_objective(stage))?;
            self.stage = Some((stage, o));
        }
        Ok(&mut self.stage.as_mut().expect("set above").1)
    }

    /// Stage `stage`'s objective's unions for the Gauss–Newton model, if it is built.
    pub(crate) fn stage_union(&self, stage: usize) -> Option<Vec<f64>> {
        self.stage
            .as_ref()
            .filter(|(k, _)| *k == stage)
            .map(|(_, o)| o.model_union().to_vec())
    }

    /// Computes this worker's share of `request` — the one function every step runs.
    ///
    /// Errors: a stage or rotation beyond the settings', a malformed request.
    pub(crate) fn work(&mut self, setup: &FitSetup, request: &Request) -> Result<Response> {
        match request {
            Request::Search { start, first, count } => {
                start.validate()?;
                let end = first
                    .checked_add(*count)
                    .filter(|&e| e <= setup.rotations.len())
                    .ok_or_else(|| {
                        Error::Settings(format!(
                            "search rotations {first}..+{count} of {}",
                            setup.rotations.len()
                        ))
                    })?;
                let targets = self.search_objective(setup)?.targets();
                let candidates = score_rotations(
                    &setup.search_model.mesh,
                    targets,
                    &setup.rotations[*first..end],
                    start,
                    setup,
                );
                Ok(Response::Candidates {
                    first: *first,
                    candidates,
                })
            }
            Request::Evaluate {
                stage,
                pose,
                kind,
                model_union,
            } => {
                pose.validate()?;
                if model_union.len() != setup.views.len() {
                    return Err(Error::Settings(format!(
                        "{} unions for {} views",
                        model_union.len(),
                        setup.views.len()
                    )));
                }
                let union: Vec<f64> = self.mine.iter().map(|&v| model_union[v]).collect();
                let objective = self.stage_objective(setup, *stage)?;
                let model = setup.model_for(*stage);
                let parts = objective.view_parts(model, pose, *kind, &union)?;
                Ok(Response::Parts {
                    views: self.mine.clone(),
                    parts,
                })
            }
        }
    }
}

/// Scores `rotations` (re-fitting translation and scale) from the start pose `start`.
fn score_rotations(
    search_mesh: &Mesh,
    targets: &[crate::loss::target::ViewTarget],
    rotations: &[DMat3],
    start: &Pose,
    setup: &FitSetup,
) -> Vec<Candidate> {
    let settings = &setup.settings;
    let centre = setup.centre;
    let c = start.apply(centre);
    let score = |r: &DMat3, bits: &mut BitMask| {
        let pose = Pose {
            rotation: *r,
            translation: c - *r * (start.scale * centre),
            scale: start.scale,
        };
        search::score_candidate(
            search_mesh,
            targets,
            pose,
            centre,
            settings.search.refit_rounds,
            settings.scale_mode.fits_scale(),
            bits,
        )
    };
    #[cfg(not(target_arch = "wasm32"))]
    {
        use rayon::prelude::*;
        rotations
            .par_iter()
            .map_init(|| BitMask::empty(0, 0), |bits, r| score(r, bits))
            .collect()
    }
    #[cfg(target_arch = "wasm32")]
    {
        let mut bits = BitMask::empty(0, 0);
        rotations.iter().map(|r| score(r, &mut bits)).collect()
    }
}

/// A worker over some of a fit's views with its own [`FitSetup`] (module doc).
pub struct Shard {
    setup: FitSetup,
    worker: Worker,
}

impl Shard {
    /// A shard of the fit of `mesh`, `views` and `settings`, computing the parts of views
    /// `mine` (and any search batch).
    ///
    /// Errors: invalid settings or mesh, or a view index beyond the views.
    pub fn new(mesh: Mesh, views: Vec<View>, mine: Vec<usize>, settings: crate::FitSettings) -> Result<Shard> {
        if let Some(&v) = mine.iter().find(|&&v| v >= views.len()) {
            return Err(Error::Settings(format!("shard: no view {v} of {}", views.len())));
        }
        Ok(Shard {
            setup: FitSetup::new(mesh, views, settings)?,
            worker: Worker::new(mine),
        })
    }

    /// The views this shard computes.
    pub fn views(&self) -> &[usize] {
        &self.worker.mine
    }

    /// Computes its share of `request`.
    ///
    /// Errors: a stage or rotation beyond the settings', a malformed request.
    pub fn work(&mut self, request: &Request) -> Result<Response> {
        self.worker.work(&self.setup, request)
    }
}
