//! The multi-view objective (SPEC §4): per view, render the soft silhouette, compare
//! it with the mask by `λ1·IoU + λ2·contour`, and back-propagate to the 9 pose
//! parameters; over views, the mean. Also the Gauss–Newton normal equations of the
//! per-pixel residuals `A_p − M_p`.
//!
//! Pose-gradient order: `[ω0, ω1, ω2, t0, t1, t2, ls0, ls1, ls2]` — ω the rotation
//! perturbation on the right (`R·exp([ω]×)`, ω = 0 at the current pose), t the
//! translation, ls the log scale (`s = exp(ls)`).

use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::loss::contour::ContourTarget;
use crate::loss::iou::{soft_iou_loss, soft_iou_sums};
use crate::mask::Mask;
use crate::mesh::Mesh;
use crate::pose::Pose;
use crate::raster::soft::{SoftRasterizer, SoftSettings};
use crate::raster::soft_backward::{NormalEquations, POSE_DIM};

/// Weights of the two loss terms.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LossSettings {
    /// λ1, weight of the soft IoU loss (default 1.0).
    pub lambda_iou: f64,
    /// λ2, weight of the contour loss (default 1.0). The contour loss is about
    /// ½(δ/r)² for a misalignment of δ pixels of an object of radius r pixels, the
    /// IoU loss about 4δ/(πr): with λ2 = 1 the IoU term leads near the optimum and the
    /// contour term when render and mask barely overlap.
    pub lambda_contour: f64,
}

impl Default for LossSettings {
    fn default() -> Self {
        LossSettings {
            lambda_iou: 1.0,
            lambda_contour: 1.0,
        }
    }
}

impl LossSettings {
    /// Checks that both weights are finite and non-negative.
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [("lambda_iou", self.lambda_iou), ("lambda_contour", self.lambda_contour)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::Settings(format!(
                    "{name} must be a non-negative number, got {v}"
                )));
            }
        }
        Ok(())
    }
}

/// A mask prepared as a loss target at one resolution.
#[derive(Debug, Clone, PartialEq)]
pub struct MaskTarget {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// 0/1 per pixel, row-major.
    pub mask: Vec<u8>,
    /// Number of object pixels.
    pub area: usize,
    /// The contour loss's distance fields.
    pub contour: ContourTarget,
}

impl MaskTarget {
    /// Prepares `mask` (resample it first for a coarser level); `view` names it in
    /// errors. Errors: an empty mask.
    pub fn new(mask: &Mask, view: &str) -> Result<MaskTarget> {
        let contour = ContourTarget::new(mask, view)?;
        let data: Vec<u8> = mask.data.iter().map(|&v| (v != 0) as u8).collect();
        Ok(MaskTarget {
            width: mask.width,
            height: mask.height,
            area: data.iter().filter(|&&v| v != 0).count(),
            mask: data,
            contour,
        })
    }
}

/// One evaluation of the loss.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LossValue {
    /// `λ1·iou + λ2·contour`.
    pub total: f64,
    /// Soft IoU loss.
    pub iou: f64,
    /// Contour loss.
    pub contour: f64,
    /// ∂total/∂θ, order `[ω0, ω1, ω2, t0, t1, t2, ls0, ls1, ls2]` (zero when not asked for).
    pub gradient: [f64; POSE_DIM],
}

/// One view of the objective: its camera (at the working resolution), its target and
/// the reusable renderer and buffers. Keep one per view across iterations.
#[derive(Debug, Clone)]
pub struct ViewObjective {
    /// The view's name (for errors).
    pub name: String,
    /// The camera, its size that of the target.
    pub camera: Camera,
    /// The mask target.
    pub target: MaskTarget,
    /// The renderer (its silhouette is the last render).
    pub raster: SoftRasterizer,
    /// The last evaluation.
    pub last: LossValue,
}

impl ViewObjective {
    /// A view from its camera and mask at the same size (scale the camera with
    /// `Camera::scaled` and the mask with `Mask::resample` for a coarser level).
    /// Errors: size mismatch or an empty mask.
    pub fn new(name: &str, camera: Camera, mask: &Mask) -> Result<ViewObjective> {
        if (mask.width, mask.height) != (camera.width, camera.height) {
            return Err(Error::View {
                view: name.into(),
                problem: format!(
                    "the mask is {}×{} but the camera is {}×{}",
                    mask.width, mask.height, camera.width, camera.height
                ),
            });
        }
        Ok(ViewObjective {
            name: name.into(),
            camera,
            target: MaskTarget::new(mask, name)?,
            raster: SoftRasterizer::new(),
            last: LossValue::default(),
        })
    }

    /// Renders at `pose` and evaluates the loss; with `gradient`, also back-propagates
    /// to the 9 pose parameters (order `[ω, t, ls]`, see the module doc).
    pub fn evaluate(
        &mut self,
        mesh: &Mesh,
        pose: &Pose,
        soft: &SoftSettings,
        loss: &LossSettings,
        gradient: bool,
    ) -> Result<LossValue> {
        loss.validate()?;
        let t = &self.target;
        let mut v = LossValue::default();
        if gradient {
            // ∂L/∂A = λ1·(I/U² − M·(1/U + I/U²)) + λ2·W: three fixed fields, one sweep.
            let (mask, cw) = (&t.mask, t.contour.gradient());
            let [g_all, g_mask, g_contour] =
                self.raster
                    .render_with_gradients(mesh, pose, &self.camera, soft, |p| [1.0, mask[p] as f64, cw[p]])?;
            let alpha = &self.raster.silhouette().alpha;
            let (i, u) = soft_iou_sums(alpha, mask);
            v.iou = 1.0 - i / u;
            v.contour = t.contour.loss(alpha);
            let (c_all, c_mask) = (
                loss.lambda_iou * i / (u * u),
                -loss.lambda_iou * (1.0 / u + i / (u * u)),
            );
            for k in 0..POSE_DIM {
                v.gradient[k] = c_all * g_all[k] + c_mask * g_mask[k] + loss.lambda_contour * g_contour[k];
            }
        } else {
            let sil = self.raster.render(mesh, pose, &self.camera, soft)?;
            v.iou = soft_iou_loss(&sil.alpha, &t.mask);
            v.contour = t.contour.loss(&sil.alpha);
        }
        v.total = loss.lambda_iou * v.iou + loss.lambda_contour * v.contour;
        self.last = v;
        Ok(v)
    }

    /// Renders at `pose` and adds the Gauss–Newton terms of the residuals
    /// `r_p = A_p − M_p`, weighted by `weight / |M|` (so that views of any size count
    /// alike), to `out`; returns the view's loss (without gradient). θ order `[ω, t, ls]`.
    pub fn normal_equations(
        &mut self,
        mesh: &Mesh,
        pose: &Pose,
        soft: &SoftSettings,
        loss: &LossSettings,
        weight: f64,
        out: &mut NormalEquations,
    ) -> Result<LossValue> {
        loss.validate()?;
        let mask = &self.target.mask;
        let w = weight / self.target.area as f64;
        let sil = self.raster.render_with_normal_equations(
            mesh,
            pose,
            &self.camera,
            soft,
            |p, a| a - mask[p] as f64,
            w,
            out,
        )?;
        let mut v = LossValue {
            iou: soft_iou_loss(&sil.alpha, mask),
            contour: self.target.contour.loss(&sil.alpha),
            ..LossValue::default()
        };
        v.total = loss.lambda_iou * v.iou + loss.lambda_contour * v.contour;
        self.last = v;
        Ok(v)
    }
}

/// The mean over `views` of the loss (and, with `gradient`, of its 9-gradient) at
/// `pose`; each view's own value is left in its `last`. Errors: no views, or any
/// view's error.
pub fn evaluate_views(
    views: &mut [ViewObjective],
    mesh: &Mesh,
    pose: &Pose,
    soft: &SoftSettings,
    loss: &LossSettings,
    gradient: bool,
) -> Result<LossValue> {
    if views.is_empty() {
        return Err(Error::Settings("the objective needs at least one view".into()));
    }
    let mut mean = LossValue::default();
    let k = 1.0 / views.len() as f64;
    for v in views.iter_mut() {
        let l = v.evaluate(mesh, pose, soft, loss, gradient)?;
        mean.total += k * l.total;
        mean.iou += k * l.iou;
        mean.contour += k * l.contour;
        for (m, g) in mean.gradient.iter_mut().zip(l.gradient) {
            *m += k * g;
        }
    }
    Ok(mean)
}
