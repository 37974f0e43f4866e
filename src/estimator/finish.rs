//! The end of a fit, computed once: the camera corrections when asked for, every
//! view's figures at full resolution, the verdict, the uncertainty and the
//! termination; and what is asked of a finished fit (the next best view).

use super::cameras;
use super::refine::{Track, DISTINCT_ADD, PATIENCE};
use super::{Estimator, State, Termination};
use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::mask::Mask;
use crate::mesh::Mesh;
use crate::metrics;
use crate::pose::Pose;
use crate::raster::hard;
use crate::uncertainty::{fit_uncertainty, std_dev, NoiseModel, RankedView, Uncertainty, Viewpoints};
use crate::verdict::{self, Judgement, Verdict};
use crate::view::View;

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

/// A view's figures at full resolution (IoU over the known pixels): the one function
/// behind the progress's IoUs, the result, the overlays and the page's views.
pub fn view_figures(mesh: &Mesh, pose: &Pose, view: &View) -> ViewFigures {
    let rendered = hard::render(mesh, pose, view.camera());
    ViewFigures {
        iou: metrics::hard_iou_known(&rendered, view.mask(), view.ignore()),
        hausdorff_px: metrics::hausdorff_px(&rendered, view.mask()),
        rendered,
    }
}

/// A distinct candidate is an alternative (and the fit `ambiguous`) when its mean
/// full-resolution IoU misses the masks by at most this many times the fit's miss
/// (`1 − IoU`), plus [`ALTERNATIVE_SLACK`]: the fit's own miss measures how well masks
/// like these can be explained, so a rival that misses by about as much cannot be told
/// apart from it. Calibrated on LM-O and synthetic two-view scenes (`tests/tier2/
/// ambiguity.rs`): the near-symmetric eggbox's flip, IoU 0.971 against 0.998, is not one;
/// with a factor of 2, right fits to segmented photographs (IoU 0.92) were flagged for
/// rivals that missed twice as much.
pub const ALTERNATIVE_FACTOR: f64 = 1.5;

/// See [`ALTERNATIVE_FACTOR`].
pub const ALTERNATIVE_SLACK: f64 = 0.01;

/// Whether a candidate of mean IoU `candidate` competes with a fit of mean IoU `fit`
/// ([`ALTERNATIVE_FACTOR`]).
pub fn competes(candidate: f64, fit: f64) -> bool {
    1.0 - candidate <= ALTERNATIVE_FACTOR * (1.0 - fit).max(0.0) + ALTERNATIVE_SLACK
}

/// Another pose that explains the masks nearly as well as the fit's, once done: a
/// distinct local optimum of the refinement (its "rivals", ARCHITECTURE.md "Ambiguity").
#[derive(Debug, Clone)]
pub struct Alternative {
    /// The pose.
    pub pose: Pose,
    /// Its loss at the last stage.
    pub loss: f64,
    /// Its views' figures at full resolution.
    pub views: Vec<ViewFigures>,
    /// Their mean IoU.
    pub mean_iou: f64,
    /// The rotation from the fit's pose to it, degrees (up to the object's symmetries).
    pub rotation_deg: f64,
    /// The ADD between them, scene units (up to the symmetries).
    pub add: f64,
    /// That over the object's diameter.
    pub add_rel: f64,
    /// Its own uncertainty, or why it could not be measured.
    pub uncertainty: std::result::Result<Uncertainty, String>,
}

/// What a finished fit holds.
pub(super) struct Final {
    pub pose: Pose,
    /// The winning candidate (its loss history and view weights).
    pub track: Track,
    pub views: Vec<ViewFigures>,
    pub judgement: Judgement,
    pub termination: Termination,
    /// The pose's uncertainty, or why it could not be measured.
    pub uncertainty: std::result::Result<Uncertainty, String>,
    /// The camera corrections when asked for, or why they could not be estimated.
    pub corrections: Option<std::result::Result<Vec<cameras::CameraCorrection>, String>>,
    /// Whether they were applied.
    pub camera_test: Option<cameras::CameraTest>,
    /// The other poses that explain the masks nearly as well, best first.
    pub alternatives: Vec<Alternative>,
}

impl Estimator {
    /// Ends the fit with `track`, the winner (module doc). The uncertainty is measured
    /// once, at the object-only optimum; applied camera corrections add the covariance
    /// their freedom costs (`cameras` module doc). `others` are the refinement's
    /// surviving rivals: those that [`competes`] at full resolution become the
    /// alternatives, the verdict `ambiguous`, and the ADD bound covers them too.
    pub(super) fn finish(&mut self, track: Track, others: Vec<Track>) -> Final {
        let settings = &self.setup.settings;
        let noise = NoiseModel::default();
        let mut pose = track.best_pose;
        let mut uncertainty = fit_uncertainty(
            &self.setup.model,
            &self.setup.views,
            &self.setup.windows,
            &pose,
            &track.weights,
            settings.scale_mode,
            &noise,
        )
        .map_err(|e| e.to_string());
        let (mut corrections, mut camera_test) = (None, None);
        if let Some(prior) = settings.refine_cameras {
            let last = settings.stages.last().expect("validated: at least one stage");
            let refined = uncertainty.as_ref().map_err(|e| e.clone()).and_then(|u| {
                cameras::refine(
                    &self.setup.model,
                    &self.setup.views,
                    &self.setup.windows,
                    &track.weights,
                    pose,
                    settings.scale_mode,
                    last.resolution,
                    settings.objective(last),
                    &prior,
                    &u.covariance,
                )
                .map_err(|e| e.to_string())
            });
            match refined {
                Ok(r) => {
                    if r.test.applied {
                        pose = r.pose;
                        self.input_views = Some(std::mem::replace(&mut self.setup.views, r.views));
                        if let Ok(u) = &mut uncertainty {
                            u.covariance += r.extra_covariance;
                            u.std_dev = std_dev(self.setup.mesh(), &pose, &u.covariance, u.std_dev.boundary_rms_px);
                        }
                    }
                    corrections = Some(Ok(r.corrections));
                    camera_test = Some(r.test);
                }
                Err(e) => corrections = Some(Err(e)),
            }
        }
        let settings = &self.setup.settings;
        // Not yet done: computed here, for the final pose.
        let views = self.view_figures(&pose);
        let names: Vec<&str> = self.setup.views.iter().map(|v| v.name()).collect();
        let ious: Vec<f64> = views.iter().map(|f| f.iou).collect();
        let inconsistent: Vec<String> = self
            .setup
            .views
            .iter()
            .zip(&track.weights)
            .filter(|(_, &w)| w < 0.5)
            .map(|(v, _)| v.name().to_string())
            .collect();
        let judgement = verdict::judge(&names, &ious, &inconsistent, &settings.verdict);
        let mean_iou = ious.iter().sum::<f64>() / ious.len().max(1) as f64;
        let alternatives = self.alternatives_of(&pose, mean_iou, others, &noise);
        let rivals: Vec<verdict::Rival> = alternatives
            .iter()
            .map(|a| verdict::Rival {
                mean_iou: a.mean_iou,
                rotation_deg: a.rotation_deg,
                add_rel: a.add_rel,
            })
            .collect();
        let judgement = verdict::ambiguous(judgement, mean_iou, &rivals);
        if let Ok(u) = &mut uncertainty {
            // A mixture: the truth is near the fit or near an alternative; the bound
            // reaches the farthest alternative's own 95 % bound.
            u.std_dev.add_95_alone = u.std_dev.add_95;
            for a in &alternatives {
                let own = a.uncertainty.as_ref().map_or(0.0, |v| v.std_dev.add_95);
                u.std_dev.add_95 = u.std_dev.add_95.max(a.add + own);
            }
        }
        let termination = if track.converged && judgement.verdict != Verdict::Failed {
            Termination::Converged
        } else if track.converged || track.since_best >= PATIENCE {
            Termination::Stalled
        } else {
            Termination::Completed
        };
        Final {
            pose,
            track,
            views,
            judgement,
            termination,
            uncertainty,
            corrections,
            camera_test,
            alternatives,
        }
    }

    /// The rivals still distinct from `pose` whose mean full-resolution IoU [`competes`]
    /// with `mean_iou`, best first, each with its own uncertainty.
    fn alternatives_of(&self, pose: &Pose, mean_iou: f64, others: Vec<Track>, noise: &NoiseModel) -> Vec<Alternative> {
        let mut out: Vec<Alternative> = Vec::new();
        for t in others {
            let alt = t.best_pose;
            let sep = self.setup.separation(pose, &alt);
            if sep.add_rel < DISTINCT_ADD
                || out
                    .iter()
                    .any(|a| self.setup.separation(&a.pose, &alt).add_rel < DISTINCT_ADD)
            {
                continue;
            }
            let views = self.view_figures(&alt);
            let mean = views.iter().map(|f| f.iou).sum::<f64>() / views.len().max(1) as f64;
            if !competes(mean, mean_iou) {
                continue;
            }
            let uncertainty = fit_uncertainty(
                &self.setup.model,
                &self.setup.views,
                &self.setup.windows,
                &alt,
                &t.weights,
                self.setup.settings.scale_mode,
                noise,
            )
            .map_err(|e| e.to_string());
            out.push(Alternative {
                pose: alt,
                loss: t.best_loss,
                views,
                mean_iou: mean,
                rotation_deg: sep.rotation_deg,
                add: sep.add,
                add_rel: sep.add_rel,
                uncertainty,
            });
        }
        out.sort_by(|a, b| b.mean_iou.total_cmp(&a.mean_iou));
        out
    }

    fn done(&self) -> Option<&Final> {
        match &self.state {
            State::Done(f) => Some(f),
            _ => None,
        }
    }

    /// Per-view figures at full resolution for a pose (kept for the final pose; natively
    /// the views in parallel).
    pub fn view_figures(&self, pose: &Pose) -> Vec<ViewFigures> {
        match self.done() {
            Some(f) if f.pose == *pose => f.views.clone(),
            _ => self.per_view(|v| view_figures(self.setup.mesh(), pose, v)),
        }
    }

    /// The full-resolution hard IoU of every view for a pose: [`Estimator::view_figures`]'s
    /// `iou` without the contour distances, which cost more than the render on a large
    /// image (what a progress report needs at every frame).
    pub fn view_ious(&self, pose: &Pose) -> Vec<f64> {
        match self.done() {
            Some(f) if f.pose == *pose => f.views.iter().map(|v| v.iou).collect(),
            _ => self.per_view(|v| {
                let rendered = hard::render(self.setup.mesh(), pose, v.camera());
                metrics::hard_iou_known(&rendered, v.mask(), v.ignore())
            }),
        }
    }

    /// `f` of every view, in order (natively on the machine's threads).
    fn per_view<T: Send>(&self, f: impl Fn(&View) -> T + Sync) -> Vec<T> {
        #[cfg(not(target_arch = "wasm32"))]
        {
            use rayon::prelude::*;
            self.setup.views.par_iter().map(&f).collect()
        }
        #[cfg(target_arch = "wasm32")]
        {
            self.setup.views.iter().map(f).collect()
        }
    }

    /// The verdict and the views it doubts, once done.
    pub fn judgement(&self) -> Option<&Judgement> {
        self.done().map(|f| &f.judgement)
    }

    /// The other poses that explain the masks nearly as well as the fit's, best first
    /// (empty before the fit is done, and when there are none).
    pub fn alternatives(&self) -> &[Alternative] {
        self.done().map_or(&[], |f| f.alternatives.as_slice())
    }

    /// The views' weights in the final fit (robust re-weighting; 0 for a view set
    /// aside), once done.
    pub fn view_weights(&self) -> Option<&[f64]> {
        self.done().map(|f| f.track.weights.as_slice())
    }

    /// The final pose's uncertainty once done (`Err` says why it could not be
    /// measured); `None` before.
    pub fn uncertainty(&self) -> Option<std::result::Result<&Uncertainty, &str>> {
        self.done().map(|f| f.uncertainty.as_ref().map_err(|e| e.as_str()))
    }

    /// The views' camera corrections once done with `refine_cameras` (`Err` says why
    /// they could not be estimated); `None` otherwise.
    pub fn camera_corrections(&self) -> Option<std::result::Result<&[cameras::CameraCorrection], &str>> {
        self.done()
            .and_then(|f| f.corrections.as_ref())
            .map(|c| c.as_ref().map(|v| v.as_slice()).map_err(|e| e.as_str()))
    }

    /// Once done with `refine_cameras`: how much of the loss the corrections removed
    /// and whether they were applied (`cameras` module doc "When to apply").
    pub fn camera_test(&self) -> Option<cameras::CameraTest> {
        self.done().and_then(|f| f.camera_test)
    }

    /// Asks for (or stops asking for) the camera correction, with its prior, before the
    /// fit ends (`FitSettings::refine_cameras`).
    ///
    /// Errors: the fit is already done, or the prior is out of range.
    pub fn set_refine_cameras(&mut self, prior: Option<cameras::CameraPrior>) -> Result<()> {
        if self.is_done() {
            return Err(Error::Settings("camera correction: the fit is already done".into()));
        }
        if let Some(p) = &prior {
            p.validate()?;
        }
        self.setup.settings.refine_cameras = prior;
        Ok(())
    }

    /// Candidate cameras ranked by how much a photograph from there is predicted to
    /// shrink the final pose's uncertainty — for an `ambiguous` fit, first by how well
    /// it would tell the alternatives apart — best first: `candidates`, or 64 viewpoints
    /// over `shell` around the object — [`FitSetup::suggest_views`](super::FitSetup::suggest_views)
    /// with the fit's pose and view weights (as `suggest-view` and the page).
    ///
    /// Errors: the fit is not done, or its uncertainty could not be measured.
    pub fn suggest_views(&self, candidates: Option<&[Camera]>, shell: Viewpoints) -> Result<Vec<RankedView>> {
        let Some(f) = self.done() else {
            return Err(Error::Settings("next view: the fit is not done".into()));
        };
        let alternatives: Vec<Pose> = f.alternatives.iter().map(|a| a.pose).collect();
        self.setup
            .suggest_views(&f.pose, &f.track.weights, &alternatives, candidates, shell)
    }
}
