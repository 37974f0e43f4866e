//! Work an estimator step needs, computed elsewhere: a [`Request`] names it (a search
//! batch, or every view's part of a refinement iteration), a [`Shard`] — an estimator's
//! mirror holding some of its views, in another thread or Web Worker — computes its
//! share, and [`Estimator::respond`](super::Estimator::respond) takes the
//! [`Response`]s back. The browser's pool of Workers renders the views of one
//! iteration this way; a shard's results are the estimator's own, bit for bit.

use super::settings::{FitSettings, ScaleMode};
use crate::error::{Error, Result};
use crate::loss::objective::{Objective, PartKind, ViewPart};
use crate::loss::target::{ViewTarget, Window};
use crate::mesh::Mesh;
use crate::optim::search::{self, Candidate};
use crate::pose::Pose;
use crate::raster::hard::BitMask;
use crate::raster::silhouette::RenderMesh;
use crate::view::View;
use glam::{DMat3, DVec3};

/// Scores `rotations` (re-fitting translation and scale) from the start pose `start`:
/// one search batch, the same wherever it is computed.
pub(super) fn score_rotations(
    search_mesh: &Mesh,
    targets: &[crate::loss::target::ViewTarget],
    rotations: &[DMat3],
    start: &Pose,
    centre: DVec3,
    settings: &FitSettings,
) -> Vec<Candidate> {
    let refit_scale = refits_scale(settings);
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
            refit_scale,
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

/// A shard's answer to a [`Request`].
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

/// An estimator's mirror holding some of its views (`mine`), built from the same mesh,
/// views and settings, so that its objectives are the estimator's own.
pub struct Shard {
    model: RenderMesh,
    search_model: RenderMesh,
    views: Vec<View>,
    windows: Vec<Window>,
    mine: Vec<usize>,
    settings: FitSettings,
    centre: DVec3,
    rotations: Vec<DMat3>,
    /// The search's targets (all views: a candidate is scored over every view).
    search: Option<Objective>,
    /// Stage objective over my views, and its stage.
    stage: Option<(usize, Objective)>,
}

impl Shard {
    /// A shard of the estimator of `mesh`, `views` and `settings`, computing the parts of
    /// views `mine` (and any search batch).
    ///
    /// Errors: invalid settings or mesh, or a view index beyond the views.
    pub fn new(mesh: Mesh, views: Vec<View>, mine: Vec<usize>, settings: FitSettings) -> Result<Shard> {
        settings.validate()?;
        mesh.validate("mesh")?;
        if let Some(&v) = mine.iter().find(|&&v| v >= views.len()) {
            return Err(Error::Settings(format!("shard: no view {v} of {}", views.len())));
        }
        let b = mesh.bounds().ok_or_else(|| Error::Mesh {
            file: "mesh".into(),
            problem: "has no vertices".into(),
        })?;
        let windows = views.iter().map(|v| Window::for_view(v, settings.window)).collect();
        Ok(Shard {
            search_model: RenderMesh::exact(mesh.clustered(settings.search.resolution * 3 / 8)),
            model: RenderMesh::with_detail(mesh, settings.detail_px),
            rotations: settings.search.sampling.rotations(),
            centre: b.centre(),
            views,
            windows,
            mine,
            settings,
            search: None,
            stage: None,
        })
    }

    /// The views this shard computes.
    pub fn views(&self) -> &[usize] {
        &self.mine
    }

    /// Computes its share of `request`.
    ///
    /// Errors: a stage or rotation beyond the settings', a malformed request.
    pub fn work(&mut self, request: &Request) -> Result<Response> {
        match request {
            Request::Search { start, first, count } => {
                start.validate()?;
                let end = first
                    .checked_add(*count)
                    .filter(|&e| e <= self.rotations.len())
                    .ok_or_else(|| {
                        Error::Settings(format!(
                            "search rotations {first}..+{count} of {}",
                            self.rotations.len()
                        ))
                    })?;
                if self.search.is_none() {
                    let mut s = self.settings.clone();
                    s.lambda_contour = 0.0;
                    s.lambda_iou = 1.0;
                    self.search = Some(Objective::new(
                        &self.views,
                        &self.windows,
                        s.search.resolution,
                        s.objective(&s.stages[0]),
                    )?);
                }
                let targets: &[ViewTarget] = self.search.as_ref().map(|o| o.targets()).unwrap_or_default();
                let candidates = score_rotations(
                    &self.search_model.mesh,
                    targets,
                    &self.rotations[*first..end],
                    start,
                    self.centre,
                    &self.settings,
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
                let s = self
                    .settings
                    .stages
                    .get(*stage)
                    .ok_or_else(|| Error::Settings(format!("no stage {stage}")))?;
                pose.validate()?;
                if model_union.len() != self.views.len() {
                    return Err(Error::Settings(format!(
                        "{} unions for {} views",
                        model_union.len(),
                        self.views.len()
                    )));
                }
                if self.stage.as_ref().is_none_or(|(k, _)| k != stage) {
                    let views: Vec<View> = self.mine.iter().map(|&v| self.views[v].clone()).collect();
                    let windows: Vec<Window> = self.mine.iter().map(|&v| self.windows[v]).collect();
                    let o = Objective::new(&views, &windows, s.resolution, self.settings.objective(s))?;
                    self.stage = Some((*stage, o));
                }
                let model = if s.resolution <= self.settings.search.resolution {
                    &self.search_model
                } else {
                    &self.model
                };
                let union: Vec<f64> = self.mine.iter().map(|&v| model_union[v]).collect();
                let (_, objective) = self.stage.as_mut().expect("set above");
                let parts = objective.view_parts(model, pose, *kind, &union)?;
                Ok(Response::Parts {
                    views: self.mine.clone(),
                    parts,
                })
            }
        }
    }
}

/// Whether the scale is re-fitted in the search.
pub(super) fn refits_scale(settings: &FitSettings) -> bool {
    settings.scale_mode != ScaleMode::Fixed
}
