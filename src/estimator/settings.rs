//! What a fit can be told ([`FitSettings`], whose [`Default`] is the one default of
//! every front end) and what it reports as it goes ([`Phase`], [`Progress`],
//! [`Termination`]).

use super::cameras::CameraPrior;
use crate::error::{Error, Result};
use crate::loss::objective::ObjectiveSettings;
use crate::optim::adam::AdamSettings;
use crate::optim::params::ScaleMode;
use crate::optim::schedule::{Optimiser, StageSettings};
use crate::optim::search::SearchSettings;
use crate::pose::Pose;
use crate::raster::lod::DEFAULT_DETAIL_PX;
use crate::raster::silhouette::RasterKind;
use crate::raster::silhouette::SoftSettings;
use crate::verdict::{Verdict, VerdictThresholds};
use crate::window::WindowMode;
use serde::{Deserialize, Serialize};

/// The default object window's margin on each side, as a fraction of the mask's box.
pub const OBJECT_MARGIN: f64 = 0.3;

/// Everything the fit can be told. [`FitSettings::default`] is the one default of
/// the command line, the browser, the npm package and `bench`.
#[derive(Debug, Clone)]
pub struct FitSettings {
    /// The coarse orientation search.
    pub search: SearchSettings,
    /// The coarse-to-fine refinement stages, in order.
    pub stages: Vec<StageSettings>,
    /// The optimiser of every stage (default Levenberg–Marquardt).
    pub optimiser: Optimiser,
    /// Adam's step sizes (multiplied by each stage's factor).
    pub adam: AdamSettings,
    /// Loss weight λ1 of the soft IoU term (default 1).
    pub lambda_iou: f64,
    /// Loss weight λ2 of the contour (chamfer) term (default 1).
    pub lambda_contour: f64,
    /// Loss weight of the region (colour posterior) term, in the last two stages, of the
    /// views that ask for it — a segmenter's masks, with their photographs
    /// ([`crate::View::with_colour_refinement`], `crate::loss::region`; default 1).
    /// Folded into the contour term: with λ2 = 0 there is none.
    pub lambda_region: f64,
    /// How the scale is fitted (default anisotropic).
    pub scale_mode: ScaleMode,
    /// Each view's window (default: a square around the mask, 30 % margin on each side).
    pub window: WindowMode,
    /// A stage ends for a candidate when its best loss improved by less than this
    /// (relative) over 5 iterations (default 1e-3); in the last stage that is convergence.
    pub tolerance: f64,
    /// Where the verdict's lines are drawn.
    pub verdict: VerdictThresholds,
    /// The soft rasteriser of every stage (default: the silhouette-edge one).
    pub raster: RasterKind,
    /// Down-weight, from the second stage on, a view whose loss contradicts the
    /// others' (robust weights; default on).
    pub robust: bool,
    /// Estimate a correction of every view's camera jointly with the pose, under this
    /// prior, after the stages (`fit --refine-cameras`; default off).
    pub refine_cameras: Option<CameraPrior>,
    /// The most, in pixels, a simplified level of the mesh may move a refinement
    /// render's silhouette at σ ≥ 1 px², times σ at sharper σ (`raster::lod`; default
    /// [`DEFAULT_DETAIL_PX`]; 0 renders the full mesh always).
    pub detail_px: f64,
}

impl Default for FitSettings {
    fn default() -> Self {
        FitSettings {
            search: SearchSettings::default(),
            stages: StageSettings::default_schedule(),
            optimiser: Optimiser::LevenbergMarquardt,
            adam: AdamSettings::default(),
            lambda_iou: 1.0,
            lambda_contour: 1.0,
            lambda_region: 1.0,
            scale_mode: ScaleMode::Anisotropic,
            window: WindowMode::Object { margin: OBJECT_MARGIN },
            tolerance: 1e-3,
            verdict: VerdictThresholds::default(),
            robust: true,
            raster: RasterKind::Edge,
            refine_cameras: None,
            detail_px: DEFAULT_DETAIL_PX,
        }
    }
}

impl FitSettings {
    /// The defaults with soft rasteriser `raster` and its schedule (the default one for
    /// the silhouette-edge rasteriser, [`StageSettings::softras_schedule`] for SoftRas).
    pub fn for_raster(raster: RasterKind) -> FitSettings {
        FitSettings {
            raster,
            stages: match raster {
                RasterKind::Edge => StageSettings::default_schedule(),
                RasterKind::SoftRas => StageSettings::softras_schedule(),
            },
            ..FitSettings::default()
        }
    }

    /// The default object window (a square around the mask, 30 % margin on each side).
    pub fn window_object_default(&self) -> WindowMode {
        WindowMode::Object { margin: OBJECT_MARGIN }
    }

    /// Checks ranges, and that the rasteriser is in this build.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::Settings(m));
        self.raster.check_available()?;
        if self.stages.is_empty() {
            return bad("at least one refinement stage is needed".into());
        }
        for (i, s) in self.stages.iter().enumerate() {
            if !(s.sigma > 0.0 && s.sigma.is_finite()) || s.resolution < 8 || s.keep == 0 || s.iterations == 0 {
                return bad(format!(
                    "stage {i}: sigma must be > 0, resolution ≥ 8, keep ≥ 1 and iterations ≥ 1"
                ));
            }
        }
        if self.search.keep == 0 || self.search.resolution < 8 {
            return bad("search: keep ≥ 1 and resolution ≥ 8".into());
        }
        if let WindowMode::Object { margin } = self.window {
            if !(margin.is_finite() && margin >= 0.0) {
                return bad(format!("window margin must be ≥ 0, got {margin}"));
            }
        }
        if !(self.detail_px.is_finite() && self.detail_px >= 0.0) {
            return bad(format!(
                "detail (--detail-px) must be a number ≥ 0 pixels, got {}",
                self.detail_px
            ));
        }
        if let Some(p) = &self.refine_cameras {
            p.validate()?;
        }
        self.stage_objective(self.stages.len() - 1).validate()
    }

    /// The objective's settings at `stage` (no region term).
    pub fn objective(&self, stage: &StageSettings) -> ObjectiveSettings {
        ObjectiveSettings {
            soft: SoftSettings {
                sigma: stage.sigma,
                eps: 1e-4,
            },
            lambda_iou: self.lambda_iou,
            lambda_contour: self.lambda_contour,
            lambda_region: 0.0,
            raster: self.raster,
        }
    }

    /// Refinement stage `i`'s objective settings: [`FitSettings::objective`], with the
    /// region term in the last two stages (a boundary refinement: the coarse stages
    /// follow the masks alone).
    pub fn stage_objective(&self, i: usize) -> ObjectiveSettings {
        let mut o = self.objective(&self.stages[i.min(self.stages.len() - 1)]);
        if i + 2 >= self.stages.len() {
            o.lambda_region = self.lambda_region;
        }
        o
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

/// Why the fit stopped. A fit whose verdict is `failed` is never `converged`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Termination {
    /// The loss stopped improving by more than the tolerance, at a pose the views accept.
    Converged,
    /// The schedule ran to its end: the last stage did all its iterations, the loss
    /// still falling slowly (a finished fit; the verdict says whether it is good).
    Completed,
    /// The loss stopped improving at a pose the views reject, or rose or stayed flat
    /// for long: the best pose so far was kept.
    Stalled,
}

impl Termination {
    /// What a user is told: `"converged"`, `"schedule completed"` or `"stalled (best
    /// pose kept)"` — a fit that ran its schedule to the end did not fail to converge.
    pub fn describe(self) -> &'static str {
        match self {
            Termination::Converged => "converged",
            Termination::Completed => "schedule completed",
            Termination::Stalled => "stalled (best pose kept)",
        }
    }
}

/// A snapshot after a step, for display.
#[derive(Debug, Clone, Serialize)]
pub struct Progress {
    /// Current phase.
    pub phase: Phase,
    /// Optimiser iterations done so far (all candidates, all stages).
    pub iteration: usize,
    /// Search candidates scored so far.
    pub searched: usize,
    /// Number of search candidates in all.
    pub search_total: usize,
    /// Refinement stage (0-based).
    pub stage: usize,
    /// Candidate index being refined.
    pub candidate: usize,
    /// The loss at the current pose (NaN during the search).
    pub loss: f64,
    /// Hard IoU per view at the current pose, at the current stage's resolution
    /// (filled by [`Estimator::progress`](crate::Estimator::progress), empty after
    /// [`Estimator::step`](crate::Estimator::step)).
    pub view_iou: Vec<f64>,
    /// The current pose.
    #[serde(skip)]
    pub pose: Pose,
    /// Why the fit stopped, once done.
    pub termination: Option<Termination>,
    /// The verdict, once done.
    pub verdict: Option<Verdict>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_rasteriser_gets_its_own_schedule() {
        let last = |s: &FitSettings| s.stages.last().unwrap().sigma;
        let edge = FitSettings::for_raster(RasterKind::Edge);
        let soft = FitSettings::for_raster(RasterKind::SoftRas);
        assert_eq!(edge.stages, FitSettings::default().stages);
        assert_eq!((edge.raster, soft.raster), (RasterKind::Edge, RasterKind::SoftRas));
        assert_eq!(last(&edge), 0.0005);
        assert_eq!(last(&soft), 0.02);
        assert_eq!(edge.stages.len(), soft.stages.len());
        assert!(edge.validate().is_ok() && soft.validate().is_ok());
    }
}
