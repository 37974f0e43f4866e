//! The multi-view objective (SPEC §4, the paper's loss): per view, render the soft
//! silhouette A in the view's window and compare it with the mask M over the known
//! pixels by `L_v = λ1·IoU_v + λ2·C_v` (soft IoU loss and the chamfer-type contour
//! term of [`crate::loss::contour`]); over views, the weighted mean
//! `L = Σ w_v·L_v / Σ w_v` (weights 1 unless the estimator down-weights a view that
//! contradicts the others). One [`Objective`] serves the search (hard IoUs), every
//! refinement stage (value, 9-gradient, Gauss–Newton model), `loss`, `bench` and the
//! tests.
//!
//! Pose-gradient order: `[ω0, ω1, ω2, t0, t1, t2, ls0, ls1, ls2]` — ω the rotation
//! perturbation on the right (`R·exp([ω]×)`), t the translation, ls the log scale.
//!
//! **The Gauss–Newton model** ([`Objective::normal_equations`]): the loss is a sum
//! of per-pixel terms `ℓ_p(A_p) ≥ 0`. The soft IoU loss is exactly an L1 distance,
//! `1 − I/U = Σ_p |A_p − M_p| / U` (for A ∈ [0, 1], M ∈ {0, 1}), and the contour
//! term is `Σ_p [A_p·d_out + (1 − A_p)·d_in]/N`. Writing each as a residual
//! `r_p = √(2ℓ_p)` (so that `½Σr² = L` exactly) gives the Gauss–Newton curvature
//! `Σ_p ℓ'_p²/(2ℓ_p) · J_p J_pᵀ`, `J_p = ∂A_p/∂θ` — for the IoU term the
//! iteratively-reweighted least-squares weights `1/(2U·|A_p − M_p|)` of an L1 fit,
//! with U taken from the view's previous evaluation (so that one sweep accumulates
//! one 9×9 matrix).
//! The gradient in the equations is the exact gradient of L (U's own dependence on A
//! included), and the Levenberg–Marquardt acceptance test uses L itself, so LM
//! minimises the paper's loss, not a surrogate.

use crate::error::{Error, Result};
use crate::loss::iou::UNION_EPS;
use crate::loss::target::ViewTarget;
use crate::mesh::Mesh;
use crate::pose::{Mat9, Pose, Vec9};
use crate::raster::hard::{render_bits_into, BitMask};
use crate::raster::project::{project_mesh, POSE_DIM};
use crate::raster::silhouette::SoftSettings;
use crate::raster::silhouette::{RasterKind, RenderMesh, SilhouetteRenderer};
use crate::view::View;
use crate::window::Window;
#[cfg(not(target_arch = "wasm32"))]
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// The objective's settings at one stage.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObjectiveSettings {
    /// Soft-silhouette σ (pixel², at the stage's canvas) and cut-off ε.
    pub soft: SoftSettings,
    /// λ1, weight of the soft IoU loss.
    pub lambda_iou: f64,
    /// λ2, weight of the contour (chamfer) term.
    pub lambda_contour: f64,
    /// Weight of the region (colour posterior) term of the views that ask for it
    /// (`crate::loss::region`; 0: none). It is folded into the contour term: with
    /// λ2 = 0 there is none.
    pub lambda_region: f64,
    /// The soft rasteriser.
    pub raster: RasterKind,
}

impl ObjectiveSettings {
    /// Checks σ, ε and that the weights are finite, non-negative and not both zero.
    pub fn validate(&self) -> Result<()> {
        self.soft.validate()?;
        for (name, v) in [
            ("lambda_iou", self.lambda_iou),
            ("lambda_contour", self.lambda_contour),
            ("lambda_region", self.lambda_region),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::Settings(format!(
                    "{name} must be a non-negative number, got {v}"
                )));
            }
        }
        if self.lambda_iou + self.lambda_contour == 0.0 {
            return Err(Error::Settings("λ1 (IoU) and λ2 (contour) cannot both be 0".into()));
        }
        Ok(())
    }
}

/// Gauss–Newton normal equations of the objective at a pose (θ order `[ω, t, ls]`).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct NormalEquations {
    /// The curvature model `Σ c_p·J_p J_pᵀ` (9×9, symmetric).
    pub jtj: Mat9,
    /// The exact gradient of the loss.
    pub jtr: Vec9,
    /// The loss.
    pub cost: f64,
}

impl NormalEquations {
    /// Adds `other` scaled by `weight`.
    pub fn add_scaled(&mut self, other: &NormalEquations, weight: f64) {
        self.jtj += other.jtj * weight;
        self.jtr += other.jtr * weight;
        self.cost += weight * other.cost;
    }
}

/// One view's share of an evaluation.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ViewValue {
    /// `λ1·iou + λ2·contour`.
    pub total: f64,
    /// Soft IoU loss, in [0, 1].
    pub iou: f64,
    /// Contour term (0 when λ2 = 0 or the mask vanished at this resolution).
    pub contour: f64,
}

/// One evaluation of the objective.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Evaluation {
    /// The weighted mean of the views' totals.
    pub total: f64,
    /// Each view's values.
    pub views: Vec<ViewValue>,
    /// ∂total/∂θ (zero when not asked for).
    pub gradient: [f64; POSE_DIM],
}

/// The objective over a set of views at one resolution (module doc). Keep it across
/// iterations: it holds one renderer per view and reuses their buffers.
#[derive(Debug, Clone)]
pub struct Objective {
    targets: Vec<ViewTarget>,
    rasters: Vec<SilhouetteRenderer>,
    weights: Vec<f64>,
    settings: ObjectiveSettings,
    bits: BitMask,
    /// Each view's soft union U at its last evaluation, for the Gauss–Newton model.
    model_union: Vec<f64>,
}

/// `Σ a` over known pixels, and `Σ a` over known object pixels, of one view.
fn iou_sums(t: &ViewTarget, alpha: &[f64]) -> (f64, f64) {
    let (mut inter, mut sum_a) = (0.0, 0.0);
    match &t.known {
        None => {
            for (&a, &m) in alpha.iter().zip(&t.mask) {
                sum_a += a;
                if m != 0 {
                    inter += a;
                }
            }
        }
        Some(k) => {
            for ((&a, &m), &k) in alpha.iter().zip(&t.mask).zip(k) {
                if k != 0 {
                    sum_a += a;
                    if m != 0 {
                        inter += a;
                    }
                }
            }
        }
    }
    (inter, sum_a + t.area - inter + UNION_EPS)
}

impl Objective {
    /// The objective of `views`, each seen through its window (`windows[i]`) at
    /// `resolution` pixels across it.
    ///
    /// Errors: invalid settings, or a different number of windows and views.
    pub fn new(views: &[View], windows: &[Window], resolution: u32, settings: ObjectiveSettings) -> Result<Objective> {
        settings.validate()?;
        if views.is_empty() || views.len() != windows.len() {
            return Err(Error::Settings(format!(
                "the objective needs one window per view and at least one view (got {} views, {} windows)",
                views.len(),
                windows.len()
            )));
        }
        let contour = settings.lambda_contour > 0.0;
        let region = if contour {
            settings.lambda_region / settings.lambda_contour
        } else {
            0.0
        };
        let targets = views
            .iter()
            .zip(windows)
            .map(|(v, w)| ViewTarget::with_region(v, *w, resolution, contour, region))
            .collect::<Result<Vec<_>>>()?;
        Ok(Objective {
            model_union: targets.iter().map(|t| t.area.max(1.0) + UNION_EPS).collect(),
            rasters: vec![SilhouetteRenderer::new(settings.raster); targets.len()],
            weights: vec![1.0; targets.len()],
            targets,
            settings,
            bits: BitMask::empty(0, 0),
        })
    }

    /// The views' targets.
    pub fn targets(&self) -> &[ViewTarget] {
        &self.targets
    }

    /// The settings.
    pub fn settings(&self) -> &ObjectiveSettings {
        &self.settings
    }

    /// Changes σ/ε (the targets stay); errors on invalid values.
    pub fn set_soft(&mut self, soft: SoftSettings) -> Result<()> {
        soft.validate()?;
        self.settings.soft = soft;
        Ok(())
    }

    /// The views' weights in the mean (all 1 by default).
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// Sets the views' weights in the mean (non-negative, not all zero; one per view).
    pub fn set_weights(&mut self, weights: &[f64]) -> Result<()> {
        if weights.len() != self.targets.len()
            || weights.iter().any(|w| !(w.is_finite() && *w >= 0.0))
            || weights.iter().sum::<f64>() <= 0.0
        {
            return Err(Error::Settings(format!(
                "view weights must be {} non-negative numbers, not all zero",
                self.targets.len()
            )));
        }
        self.weights = weights.to_vec();
        Ok(())
    }

    /// The last render's soft silhouette of view `i` (canvas pixels, row-major).
    pub fn alpha(&self, i: usize) -> &[f64] {
        self.rasters[i].alpha()
    }

    fn norm(&self) -> f64 {
        self.weights.iter().sum::<f64>()
    }

    /// Evaluates every view (in parallel natively; one after the other in wasm).
    fn parts(&mut self, mesh: &RenderMesh, pose: &Pose, kind: PartKind) -> Result<Vec<ViewPart>> {
        let union = self.model_union.clone();
        self.parts_with(mesh, pose, kind, &union)
    }

    /// Evaluates every view with the Gauss–Newton model's unions `model_union` (one per view).
    fn parts_with(
        &mut self,
        mesh: &RenderMesh,
        pose: &Pose,
        kind: PartKind,
        model_union: &[f64],
    ) -> Result<Vec<ViewPart>> {
        let settings = self.settings;
        let scale: Vec<f64> = model_union.iter().map(|u| settings.lambda_iou / u).collect();
        let job = |(i, (raster, target)): (usize, (&mut SilhouetteRenderer, &ViewTarget))| {
            view_part(raster, target, &settings, mesh, pose, kind, scale[i])
        };
        #[cfg(not(target_arch = "wasm32"))]
        let parts: Vec<Result<ViewPart>> = self
            .rasters
            .par_iter_mut()
            .zip(self.targets.par_iter())
            .enumerate()
            .map(job)
            .collect();
        #[cfg(target_arch = "wasm32")]
        let parts: Vec<Result<ViewPart>> = self
            .rasters
            .iter_mut()
            .zip(self.targets.iter())
            .enumerate()
            .map(job)
            .collect();
        parts.into_iter().collect()
    }

    /// Combines the views' parts into the weighted mean, its gradient and its
    /// Gauss–Newton model.
    fn combine(&mut self, parts: &[ViewPart]) -> (Evaluation, NormalEquations) {
        let mut ev = Evaluation::default();
        let mut ne = NormalEquations::default();
        let norm = self.norm();
        let (l1, l2) = (self.settings.lambda_iou, self.settings.lambda_contour);
        for (i, part) in parts.iter().enumerate() {
            let (inter, union) = (part.inter, part.union);
            self.model_union[i] = union;
            let iou = 1.0 - inter / union;
            let contour = if l2 > 0.0 { part.contour } else { 0.0 };
            let v = ViewValue {
                total: l1 * iou + l2 * contour,
                iou,
                contour,
            };
            let w = self.weights[i] / norm;
            let (c_mask, c_back) = (-l1 / union, l1 * inter / (union * union));
            for a in 0..POSE_DIM {
                ne.jtr[a] += w * (c_mask * part.g[0][a] + c_back * part.g[1][a] + l2 * part.g[2][a]);
                // Only the upper triangle was accumulated.
                for b in 0..POSE_DIM {
                    ne.jtj[(a, b)] += w * if b >= a { part.h[(a, b)] } else { part.h[(b, a)] };
                }
            }
            ev.total += w * v.total;
            ev.views.push(v);
        }
        ne.cost = ev.total;
        ev.gradient = ne.jtr.into();
        (ev, ne)
    }

    /// Each view's soft union at its last evaluation: what a worker evaluating some of
    /// the views needs for the Gauss–Newton model ([`Objective::view_parts`]).
    pub fn model_union(&self) -> &[f64] {
        &self.model_union
    }

    /// Evaluates every view of this objective at `pose` — for a worker that holds some of
    /// an estimator's views — with the unions the coordinating objective's
    /// [`Objective::model_union`] gives for them.
    ///
    /// Errors: a `model_union` of another length, or a render's error.
    pub fn view_parts(
        &mut self,
        mesh: &RenderMesh,
        pose: &Pose,
        kind: PartKind,
        model_union: &[f64],
    ) -> Result<Vec<ViewPart>> {
        if model_union.len() != self.targets.len() || model_union.iter().any(|u| !(u.is_finite() && *u > 0.0)) {
            return Err(Error::Settings(format!(
                "view parts: {} positive unions needed, got {:?}",
                self.targets.len(),
                model_union
            )));
        }
        self.parts_with(mesh, pose, kind, model_union)
    }

    /// Combines every view's part (in view order, as computed by [`Objective::view_parts`]
    /// here or elsewhere) into the loss, its gradient and its Gauss–Newton model.
    ///
    /// Errors: not one part per view.
    pub fn combine_parts(&mut self, parts: &[ViewPart]) -> Result<(Evaluation, NormalEquations)> {
        if parts.len() != self.targets.len() {
            return Err(Error::Settings(format!(
                "{} view parts for {} views",
                parts.len(),
                self.targets.len()
            )));
        }
        Ok(self.combine(parts))
    }

    /// Moves view `i`'s camera to other extrinsics (a camera correction): its window,
    /// canvas and intrinsics stay.
    pub fn set_extrinsics(&mut self, i: usize, rotation: glam::DMat3, translation: glam::DVec3) {
        if let Some(t) = self.targets.get_mut(i) {
            t.camera.rotation = rotation;
            t.camera.translation = translation;
        }
    }

    /// The objective at `pose`, without gradient.
    pub fn value(&mut self, mesh: &RenderMesh, pose: &Pose) -> Result<Evaluation> {
        let parts = self.parts(mesh, pose, PartKind::Value)?;
        let (mut ev, _) = self.combine(&parts);
        ev.gradient = [0.0; POSE_DIM];
        Ok(ev)
    }

    /// The objective at `pose` and its exact 9-gradient, in one fused render-and-
    /// backward sweep per view.
    pub fn value_and_gradient(&mut self, mesh: &RenderMesh, pose: &Pose) -> Result<Evaluation> {
        let parts = self.parts(mesh, pose, PartKind::Gradient)?;
        Ok(self.combine(&parts).0)
    }

    /// The objective, its exact gradient and its Gauss–Newton curvature model (module
    /// doc) at `pose`, in one render-and-Jacobian sweep per view.
    pub fn normal_equations(&mut self, mesh: &RenderMesh, pose: &Pose) -> Result<(Evaluation, NormalEquations)> {
        let parts = self.parts(mesh, pose, PartKind::GaussNewton)?;
        Ok(self.combine(&parts))
    }

    /// Hard IoU per view (over known pixels) of `mesh` at `pose`.
    pub fn hard_ious(&mut self, mesh: &Mesh, pose: &Pose) -> Vec<f64> {
        let mut bits = std::mem::replace(&mut self.bits, BitMask::empty(0, 0));
        let out = self
            .targets
            .iter()
            .map(|t| {
                let proj = project_mesh(mesh, pose, &t.camera);
                render_bits_into(&proj, &mesh.triangles, &t.camera, &mut bits);
                t.hard_iou(&bits)
            })
            .collect();
        self.bits = bits;
        out
    }
}

/// What a view's evaluation computes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PartKind {
    /// The loss alone.
    Value,
    /// The loss and its gradient (Adam).
    Gradient,
    /// The loss, its gradient and its Gauss–Newton model (LM).
    GaussNewton,
}

/// One view's share of an evaluation — what a worker computing some views of an
/// iteration hands back ([`Objective::view_parts`], [`Objective::combine_parts`]): the
/// IoU's sums, the contour term, the 9-gradients of `Σ M·A`, `Σ (1 − M)·A` and `Σ W·A`
/// over known pixels (W the contour term's ∂/∂A), and the upper triangle of its
/// Gauss–Newton curvature.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ViewPart {
    /// `Σ A·M` over known pixels.
    pub inter: f64,
    /// The soft union `Σ (A + M − A·M)` over known pixels (+1e-6).
    pub union: f64,
    /// The contour term.
    pub contour: f64,
    /// The three field gradients (mask, background, contour).
    pub g: [[f64; POSE_DIM]; 3],
    /// The curvature, upper triangle (`h[(a, b)]`, b ≥ a).
    pub h: Mat9,
}

/// Evaluates one view; `iou_scale` is λ1/U of the view's previous evaluation (the
/// Gauss–Newton model's IoU weights).
fn view_part(
    raster: &mut SilhouetteRenderer,
    t: &ViewTarget,
    s: &ObjectiveSettings,
    mesh: &RenderMesh,
    pose: &Pose,
    kind: PartKind,
    iou_scale: f64,
) -> Result<ViewPart> {
    let mut part = ViewPart {
        inter: 0.0,
        union: 0.0,
        contour: 0.0,
        g: [[0.0; POSE_DIM]; 3],
        h: Mat9::zeros(),
    };
    let contour = t.contour.as_ref().filter(|_| s.lambda_contour > 0.0);
    let (mask, known) = (&t.mask, t.known.as_deref());
    match kind {
        PartKind::Value => {
            raster.render(mesh, pose, &t.camera, &s.soft)?;
        }
        PartKind::Gradient => {
            let cw = contour.map(|c| c.gradient());
            part.g = raster.render_with_gradients(mesh, pose, &t.camera, &s.soft, |p| {
                let k = known.map_or(1.0, |k| k[p] as f64);
                let m = mask[p] as f64;
                [m * k, (1.0 - m) * k, cw.map_or(0.0, |w| w[p])]
            })?;
        }
        PartKind::GaussNewton => {
            let mut upper = [[0.0; POSE_DIM]; POSE_DIM];
            let (g, h) = (&mut part.g, &mut upper);
            let l2 = s.lambda_contour;
            raster.render_with_jacobians(mesh, pose, &t.camera, &s.soft, |p, a, j| {
                if !t.is_known(p) {
                    return;
                }
                let m = mask[p] as f64;
                let f = if m != 0.0 { 0 } else { 1 };
                for k in 0..POSE_DIM {
                    g[f][k] += j[k];
                }
                // IRLS weight of |A − M|, and the contour's w²/(2ℓ).
                let mut c = iou_scale * 0.5 / (a - m).abs().max(1e-12);
                if let Some(ct) = contour {
                    let w = ct.gradient()[p];
                    for k in 0..POSE_DIM {
                        g[2][k] += w * j[k];
                    }
                    c += l2 * 0.5 * w * w / ct.pixel_loss(p, a).max(1e-300);
                }
                accumulate(h, j, c);
            })?;
            part.h = Mat9::from_fn(|a, b| upper[a][b]);
        }
    }
    let alpha = raster.alpha();
    (part.inter, part.union) = iou_sums(t, alpha);
    if let Some(c) = contour {
        part.contour = c.loss(alpha);
    }
    Ok(part)
}

/// `h += c·j jᵀ` on the upper triangle.
#[inline(always)]
fn accumulate(h: &mut [[f64; POSE_DIM]; POSE_DIM], j: &[f64; POSE_DIM], c: f64) {
    for a in 0..POSE_DIM {
        let ca = c * j[a];
        for b in a..POSE_DIM {
            h[a][b] += ca * j[b];
        }
    }
}
