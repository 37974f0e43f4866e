//! The result of a fit (SPEC §3): the pose in its wire form plus the quaternion and
//! the 4×4 object-to-world matrix, per-view figures, the loss history, the time
//! taken (measured by the caller: the core has no clock), the verdict with the views
//! it doubts and, given a ground truth, the error figures of SPEC §6 — measured
//! against the symmetric equivalent of the truth closest to the estimate, so that
//! the command line, the page and `eval` report the same figures.

use super::{CameraCorrection, CameraTest, Estimator, Termination};
use crate::metrics::{pose_errors, PoseErrors};
use crate::optim::params::ScaleMode;
use crate::pose::{mat3_to_rows, mat4_to_rows, Pose};
use crate::so3;
use crate::symmetry;
use crate::uncertainty::StdDev;
use crate::verdict::Verdict;
use serde::{Deserialize, Serialize};

/// A pose with every form a reader may want.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct PoseOut {
    /// 3×3 row-major rotation.
    pub rotation: [[f64; 3]; 3],
    /// Unit quaternion [w, x, y, z], w ≥ 0.
    pub quaternion: [f64; 4],
    /// Intrinsic XYZ Euler angles in degrees (display only).
    pub euler_xyz_deg: [f64; 3],
    /// Translation.
    pub translation: [f64; 3],
    /// Per-axis scale.
    pub scale: [f64; 3],
}

impl PoseOut {
    /// All forms of a pose.
    pub fn from_pose(p: &Pose) -> PoseOut {
        let q = p.quaternion();
        PoseOut {
            rotation: mat3_to_rows(p.rotation),
            quaternion: [q.w, q.x, q.y, q.z],
            euler_xyz_deg: so3::to_euler_xyz_deg(p.rotation).to_array(),
            translation: p.translation.to_array(),
            scale: p.scale.to_array(),
        }
    }
}

/// Figures of one view at the estimated pose.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct ViewResult {
    /// The view's name.
    pub name: String,
    /// Hard silhouette IoU against the mask, full resolution, over the known pixels.
    pub iou: f64,
    /// Hausdorff distance between the rendered and the mask's contours, pixels.
    pub hausdorff_px: f64,
    /// The view's weight in the final fit: 1, lower for a view the robust weighting
    /// doubts, 0 for one set aside (once done; `suggest-view` plans with it).
    #[serde(default = "one")]
    pub weight: f64,
}

fn one() -> f64 {
    1.0
}

/// The result file.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct FitResult {
    /// The estimated pose.
    pub pose: PoseOut,
    /// 4×4 object-to-world matrix, row-major.
    pub matrix: [[f64; 4]; 4],
    /// Per-view figures.
    pub views: Vec<ViewResult>,
    /// Mean per-view IoU.
    pub mean_iou: f64,
    /// The loss at every optimiser iteration of the winning candidate.
    pub loss_history: Vec<f64>,
    /// Optimiser iterations over all candidates.
    pub iterations: usize,
    /// Why the fit stopped.
    pub termination: Option<Termination>,
    /// Which scale parameters were fitted (`suggest-view` plans for the same).
    #[serde(default = "anisotropic")]
    pub scale_mode: ScaleMode,
    /// `ok`, `poor`, `ambiguous` or `failed` (see [`crate::Verdict`]); absent before the
    /// fit ends.
    #[serde(default)]
    pub verdict: Option<Verdict>,
    /// Why the verdict is not `ok`, one line each.
    #[serde(default)]
    pub verdict_reasons: Vec<String>,
    /// Views the verdict doubts.
    #[serde(default)]
    pub doubted_views: Vec<String>,
    /// The pose covariance, 9×9 rows in `[ω (rad, right tangent: R_true ≈
    /// R·exp([ω]×)), t (scene units), log s]` (`crate::uncertainty`), once done.
    #[serde(default)]
    pub covariance: Option<[[f64; 9]; 9]>,
    /// Its readable standard deviations, once done.
    #[serde(default)]
    pub std_dev: Option<StdDev>,
    /// Why the uncertainty could not be measured, when it could not.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub uncertainty_error: Option<String>,
    /// Each view's camera correction, when the fit was asked to refine the cameras.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub camera_corrections: Option<Vec<CameraCorrection>>,
    /// Why the cameras could not be corrected, when they could not.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub camera_correction_error: Option<String>,
    /// How much of the loss the corrections removed, and whether the pose and figures
    /// use them (they are applied only when they explain enough of it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub camera_test: Option<CameraTest>,
    /// Wall-clock seconds, as measured by the caller.
    pub seconds: f64,
    /// Error figures against the scene's ground truth, when it has one (against its
    /// symmetric equivalent closest to the estimate, for a symmetric object).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub errors: Option<PoseErrors>,
    /// Whether the object was found symmetric (errors then allow for it), when a
    /// ground truth was given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub symmetric: Option<bool>,
    /// Other poses that explain the masks nearly as well (verdict `ambiguous`), best
    /// first; absent when there are none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub alternatives: Vec<AlternativeOut>,
    /// The masks the fit made from photographs, and how they came about (absent when
    /// every view gave its mask).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub masks: Vec<MaskReport>,
}

/// A pose that competes with the fit's (an entry of the result's `alternatives`).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct AlternativeOut {
    /// The pose.
    pub pose: PoseOut,
    /// 4×4 object-to-world matrix, row-major.
    pub matrix: [[f64; 4]; 4],
    /// Its per-view hard IoU at full resolution, in the views' order.
    pub view_iou: Vec<f64>,
    /// Their mean.
    pub mean_iou: f64,
    /// Its loss at the last stage.
    pub loss: f64,
    /// The rotation from the fit's pose, degrees (up to the object's symmetries).
    pub rotation_deg: f64,
    /// The ADD from the fit's pose over the diameter (up to the symmetries).
    pub add_rel: f64,
    /// Its own covariance (as the result's `covariance`), when it could be measured.
    #[serde(default)]
    pub covariance: Option<[[f64; 9]; 9]>,
    /// Its own standard deviations, when measured.
    #[serde(default)]
    pub std_dev: Option<StdDev>,
    /// Its error figures against the scene's ground truth, when it has one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub errors: Option<PoseErrors>,
}

/// How one mask made from a photograph came about (an entry of the result's `masks`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MaskReport {
    /// The view's name.
    pub view: String,
    /// Where its first box came from: `"box"` (the scene's) or `"geometry"` (no box, or
    /// one far too loose: the other views' geometry gave the box within it).
    pub first_box_from: String,
    /// The first box, image pixels `[x_min, y_min, x_max, y_max]`.
    pub first_box: [f64; 4],
    /// Object pixels of each round's mask.
    pub areas: Vec<usize>,
    /// IoU of each round's mask with the previous round's (one fewer than `areas`).
    pub changes: Vec<f64>,
    /// Which of the segmenter's masks each round took (SAM: 0 its single-mask reading,
    /// 1–3 its three multimask readings); from the second round, the one closest to the
    /// fit.
    #[serde(default)]
    pub picks: Vec<usize>,
    /// The segmenter's own IoU estimate for the final mask.
    pub score: f32,
    /// IoU of the segmenter's final mask with the silhouette of the final pose.
    pub iou_with_fit: f64,
    /// What the returned mask is: `"fit"`, the final pose's silhouette where the
    /// segmenter saw the object (`segment::photo::visible`), or `"segmenter"`, the
    /// segmenter's own latest mask (while the rounds run, and after them when the two
    /// disagree — `iou_with_fit` below 0.5 — or nothing of the silhouette is kept).
    #[serde(default)]
    pub returned: String,
}

fn anisotropic() -> ScaleMode {
    ScaleMode::Anisotropic
}

impl Estimator {
    /// The result at the current (best) pose. `seconds` is the caller's measurement;
    /// `ground_truth` adds the error figures (allowing for the object's symmetries).
    pub fn result(&self, seconds: f64, ground_truth: Option<&Pose>) -> FitResult {
        let pose = self.pose();
        let figs = self.view_figures(&pose);
        let weights = self.view_weights();
        let views: Vec<ViewResult> = self
            .views()
            .iter()
            .zip(&figs)
            .enumerate()
            .map(|(i, (v, f))| ViewResult {
                name: v.name().to_string(),
                iou: f.iou,
                hausdorff_px: f.hausdorff_px,
                weight: weights.map_or(1.0, |w| w[i]),
            })
            .collect();
        let mean_iou = views.iter().map(|v| v.iou).sum::<f64>() / views.len().max(1) as f64;
        let progress = self.snapshot(Vec::new());
        let judgement = self.judgement();
        let syms = ground_truth.map(|_| symmetry::symmetries(self.mesh()));
        let errors_of = |p: &Pose| {
            let (gt, syms) = (ground_truth?, syms.as_ref()?);
            let truth = symmetry::closest_equivalent(self.mesh(), syms, p, gt);
            Some(pose_errors(self.mesh(), p, &truth))
        };
        let (errors, symmetric) = (errors_of(&pose), syms.as_ref().map(|s| s.len() > 1));
        let alternatives = self
            .alternatives()
            .iter()
            .map(|a| AlternativeOut {
                pose: PoseOut::from_pose(&a.pose),
                matrix: mat4_to_rows(a.pose.matrix()),
                view_iou: a.views.iter().map(|f| f.iou).collect(),
                mean_iou: a.mean_iou,
                loss: a.loss,
                rotation_deg: a.rotation_deg,
                add_rel: a.add_rel,
                covariance: a.uncertainty.as_ref().ok().map(|u| u.covariance_rows()),
                std_dev: a.uncertainty.as_ref().ok().map(|u| u.std_dev.clone()),
                errors: errors_of(&a.pose),
            })
            .collect();
        // Once done, `pose` is the final pose the uncertainty was measured at.
        let (covariance, std_dev, uncertainty_error) = match self.uncertainty() {
            Some(Ok(u)) => (Some(u.covariance_rows()), Some(u.std_dev.clone()), None),
            Some(Err(e)) => (None, None, Some(e.to_string())),
            None => (None, None, None),
        };
        let (camera_corrections, camera_correction_error) = match self.camera_corrections() {
            Some(Ok(c)) => (Some(c.to_vec()), None),
            Some(Err(e)) => (None, Some(e.to_string())),
            None => (None, None),
        };
        FitResult {
            camera_corrections,
            camera_correction_error,
            camera_test: self.camera_test(),
            covariance,
            std_dev,
            uncertainty_error,
            pose: PoseOut::from_pose(&pose),
            matrix: mat4_to_rows(pose.matrix()),
            views,
            mean_iou,
            loss_history: self.loss_history(),
            iterations: progress.iteration,
            termination: progress.termination,
            scale_mode: self.settings().scale_mode,
            verdict: judgement.map(|j| j.verdict),
            verdict_reasons: judgement.map(|j| j.reasons.clone()).unwrap_or_default(),
            doubted_views: judgement.map(|j| j.doubted_views.clone()).unwrap_or_default(),
            seconds,
            errors,
            symmetric,
            alternatives,
            masks: Vec::new(),
        }
    }
}
