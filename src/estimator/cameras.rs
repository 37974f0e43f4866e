//! Camera correction (`fit --refine-cameras`): a small rotation and translation per
//! view, estimated jointly with the object pose under a prior, after the object-only
//! stages.
//!
//! View v's camera becomes `exp(η_v)·T_v` (η_v = (φ, ρ) a twist in the camera frame:
//! `Y' = Y + φ × Y + ρ` for a camera-frame point Y). Seen from the world, that moves the
//! scene by a rotation `a = R_cᵀφ` about the camera's centre c and a shift `R_cᵀρ`, so
//! to first order it is a change of the object pose, `δθ = K_v δη` with
//!
//! ```text
//! δω = Rᵀ R_cᵀ δφ,   δt = −[t − c]× R_cᵀ δφ + R_cᵀ δρ,   δlog s = 0
//! ```
//!
//! and each view's Gauss–Newton model in θ (its 9×9 `H_v`, gradient `g_v`, at the last
//! stage's resolution and σ of at least 0.02 px²) gives the joint model in
//! (θ, η_1 … η_N). The prior is Gaussian: σ_rot (default 1°) on φ and σ_d·d_v
//! (default 1 % of the camera's distance to the object) on ρ. The loss is not a
//! log-likelihood, so the prior enters at the temperature `T = tr(H Σ_θ)/k` that makes
//! the loss's curvature `H` agree with the calibrated pose covariance `Σ_θ`
//! (`crate::uncertainty`): the fit minimises `L + (T/2) Σ_v η_vᵀ P_v η_v`.
//!
//! **The gauge.** Moving the object and every camera by one rigid motion changes no
//! image. Each correction's world twist is `w_v = A_v η_v` with
//! `A_v = [[R_cᵀ, 0], [[c]×R_cᵀ, R_cᵀ]]`; the corrections are constrained to
//! `Σ_v w_v = 0` (the mean motion of the cameras is zero) by working in a basis of the
//! null space of `[A_1 … A_N]` (6N − 6 parameters): the object pose carries the common
//! motion, the corrections only the cameras' disagreement.
//!
//! The pose covariance then adds what the cameras' freedom costs:
//! `T·([H_joint⁻¹]_θθ − H_θθ⁻¹)` on top of the outline's measurement covariance.
//!
//! **When to apply.** 6N − 6 more parameters always lower the loss a little, by
//! fitting the masks' noise; corrections of exact cameras cost accuracy that way
//! (docs/benchmark-history.md "Camera correction"). So the corrections are applied only when they
//! remove at least [`CameraPrior::min_reduction`] (default 15 %) of the penalised loss
//! at the object-only optimum. Measured on the Duck scenes of the test (3–4 views,
//! clean masks): exact cameras 2–6 %, cameras off by 0.7° and 1 % of their distance
//! 33–68 %. Otherwise the result keeps the object-only pose, figures and uncertainty,
//! and still lists the estimated corrections, with [`CameraTest`] saying why. (A
//! likelihood-ratio test at the calibrated temperature does not separate the two: the
//! temperature measured at an inconsistent fit absorbs the cameras' errors as noise.)

use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::loss::objective::{Objective, ObjectiveSettings};
use crate::optim::lm::Lm;
use crate::optim::params::ScaleMode;
use crate::pose::{mat4_to_rows, Pose};
use crate::pose::{Mat9, Vec9};
use crate::raster::silhouette::RenderMesh;
use crate::so3;
use crate::view::View;
use crate::window::Window;
use glam::{DMat3, DVec3};
use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};
use std::ops::AddAssign;

/// The prior on each camera's correction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraPrior {
    /// Standard deviation of the rotation, degrees (default 1).
    pub rotation_deg: f64,
    /// Standard deviation of the translation, as a fraction of the camera's distance
    /// to the object (default 0.01).
    pub distance: f64,
    /// The corrections are applied only when they remove at least this fraction of the
    /// loss (default 0.15, module doc "When to apply"); 0 applies them always.
    pub min_reduction: f64,
}

impl Default for CameraPrior {
    fn default() -> Self {
        CameraPrior {
            rotation_deg: 1.0,
            distance: 0.01,
            min_reduction: DEFAULT_MIN_REDUCTION,
        }
    }
}

impl CameraPrior {
    /// Checks ranges.
    pub fn validate(&self) -> Result<()> {
        if !(self.rotation_deg.is_finite()
            && self.rotation_deg > 0.0
            && self.distance.is_finite()
            && self.distance > 0.0)
        {
            return Err(Error::Settings(format!(
                "camera prior: the rotation (°) and the distance fraction must be > 0, got {} and {}",
                self.rotation_deg, self.distance
            )));
        }
        if !(0.0..1.0).contains(&self.min_reduction) {
            return Err(Error::Settings(format!(
                "camera correction: the minimum loss reduction must be in [0, 1), got {}",
                self.min_reduction
            )));
        }
        Ok(())
    }
}

/// The default of [`CameraPrior::min_reduction`].
pub const DEFAULT_MIN_REDUCTION: f64 = 0.15;

/// Whether the corrections were applied (module doc "When to apply").
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CameraTest {
    /// The fraction of the loss (at the object-only optimum) the corrections remove.
    pub loss_reduction: f64,
    /// The fraction required ([`CameraPrior::min_reduction`]).
    pub min_reduction: f64,
    /// Whether the pose, the figures and the uncertainty use the corrected cameras.
    pub applied: bool,
}

/// One view's estimated correction, in its camera's frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CameraCorrection {
    /// The view's name.
    pub view: String,
    /// Rotation vector φ (camera frame), degrees.
    pub rotation_deg: [f64; 3],
    /// Translation ρ (camera frame), scene units.
    pub translation: [f64; 3],
    /// |φ|, degrees.
    pub angle_deg: f64,
    /// |ρ| as a percentage of the camera's distance to the object.
    pub shift_pct: f64,
    /// The corrected world-to-camera 4×4, row-major.
    pub world_to_camera: [[f64; 4]; 4],
}

/// What the joint refinement returns.
pub(super) struct Refined {
    pub pose: Pose,
    pub views: Vec<View>,
    pub corrections: Vec<CameraCorrection>,
    /// The covariance the cameras' freedom adds to the pose's.
    pub extra_covariance: Mat9,
    /// Whether to apply them.
    pub test: CameraTest,
}

/// Joint Levenberg–Marquardt iterations.
const ITERATIONS: usize = 40;

/// The least σ (px²) of the joint refinement: the last stage's nearly hard silhouette
/// leaves too few soft pixels for 6N − 6 more parameters (measured: with σ = 0.0005
/// the corrections of cameras 0.7° off were applied in 6 of 10 scenes and left a
/// median rotation error of 1.26°, against 10 of 10 and 0.6° at 0.02).
const JOINT_SIGMA: f64 = 0.02;

/// A camera corrected by the twist `eta` = (φ, ρ) in its frame.
fn corrected(cam: &Camera, eta: &[f64]) -> (DMat3, DVec3) {
    let r = so3::exp(DVec3::new(eta[0], eta[1], eta[2]));
    (
        so3::orthonormalize(r * cam.rotation),
        r * cam.translation + DVec3::new(eta[3], eta[4], eta[5]),
    )
}

fn skew(v: DVec3) -> DMat3 {
    DMat3::from_cols(
        DVec3::new(0.0, v.z, -v.y),
        DVec3::new(-v.z, 0.0, v.x),
        DVec3::new(v.y, -v.x, 0.0),
    )
}

/// `K_v` (9×6): the object-pose change that a camera-frame twist of `(r_c, c)` amounts to.
fn pose_of_twist(pose: &Pose, r_c: DMat3, c: DVec3) -> DMatrix<f64> {
    let rct = r_c.transpose();
    let top = pose.rotation.transpose() * rct;
    let mid = -(skew(pose.translation - c) * rct);
    let mut k = DMatrix::zeros(9, 6);
    for i in 0..3 {
        for j in 0..3 {
            k[(i, j)] = top.col(j)[i];
            k[(3 + i, j)] = mid.col(j)[i];
            k[(3 + i, 3 + j)] = rct.col(j)[i];
        }
    }
    k
}

/// `[A_1 … A_N]`: the corrections' world twists summed (module doc).
fn world_twists(cams: &[Camera]) -> DMatrix<f64> {
    let n = cams.len();
    let mut a = DMatrix::zeros(6, 6 * n);
    for (v, cam) in cams.iter().enumerate() {
        let rct = cam.rotation.transpose();
        let cx = skew(cam.centre()) * rct;
        for i in 0..3 {
            for j in 0..3 {
                a[(i, 6 * v + j)] = rct.col(j)[i];
                a[(3 + i, 6 * v + j)] = cx.col(j)[i];
                a[(3 + i, 6 * v + 3 + j)] = rct.col(j)[i];
            }
        }
    }
    a
}

/// A basis of the corrections that keep the cameras' mean world motion zero.
fn gauge_basis(cams: &[Camera]) -> DMatrix<f64> {
    let n = cams.len();
    let a = world_twists(cams);
    // The eigenvectors of AᵀA beyond the largest six span A's null space.
    let svd = (a.transpose() * &a).symmetric_eigen();
    let mut order: Vec<usize> = (0..6 * n).collect();
    order.sort_by(|&i, &j| svd.eigenvalues[i].total_cmp(&svd.eigenvalues[j]));
    let keep = &order[..6 * n - 6];
    DMatrix::from_fn(6 * n, keep.len(), |r, c| svd.eigenvectors[(r, keep[c])])
}

/// One joint evaluation: the penalised loss and the reduced normal equations.
struct Joint {
    cost: f64,
    h: DMatrix<f64>,
    g: DVector<f64>,
    /// `H_θθ` over the free pose directions.
    h_pose: DMatrix<f64>,
}

/// The joint refinement of the pose and the views' camera corrections (module doc).
/// `pose_covariance` is the calibrated covariance at `pose` (for the temperature).
///
/// Errors: a render fails, or the information is degenerate.
#[allow(clippy::too_many_arguments)]
pub(super) fn refine(
    model: &RenderMesh,
    views: &[View],
    windows: &[Window],
    weights: &[f64],
    pose: Pose,
    mode: ScaleMode,
    resolution: u32,
    settings: ObjectiveSettings,
    prior: &CameraPrior,
    pose_covariance: &Mat9,
) -> Result<Refined> {
    prior.validate()?;
    let settings = ObjectiveSettings {
        soft: crate::raster::silhouette::SoftSettings {
            sigma: settings.soft.sigma.max(JOINT_SIGMA),
            ..settings.soft
        },
        ..settings
    };
    let n = views.len();
    let mut objectives: Vec<Objective> = views
        .iter()
        .zip(windows)
        .map(|(v, w)| Objective::new(std::slice::from_ref(v), std::slice::from_ref(w), resolution, settings))
        .collect::<Result<_>>()?;
    let norm: f64 = weights.iter().sum::<f64>().max(f64::MIN_POSITIVE);
    let wn: Vec<f64> = weights.iter().map(|w| w / norm).collect();
    let cams: Vec<Camera> = views.iter().map(|v| *v.camera()).collect();
    let centre = model.mesh.bounds().map_or(pose.translation, |b| pose.apply(b.centre()));
    let sd_rot = prior.rotation_deg.to_radians();
    let precision: Vec<[f64; 6]> = cams
        .iter()
        .map(|c| {
            let sd_t = (prior.distance * c.centre().distance(centre)).max(1e-12);
            let (a, b) = (1.0 / (sd_rot * sd_rot), 1.0 / (sd_t * sd_t));
            [a, a, a, b, b, b]
        })
        .collect();
    let p = mode.basis();
    let k = p.ncols();
    let gauge = gauge_basis(&cams);
    let m = gauge.ncols();
    let mut basis = DMatrix::zeros(9 + 6 * n, k + m);
    basis.view_mut((0, 0), (9, k)).copy_from(&p);
    basis.view_mut((9, k), (6 * n, m)).copy_from(&gauge);

    let mut temperature = f64::NAN;
    let mut evaluate = |pose: &Pose, eta: &DVector<f64>, temperature: &mut f64| -> Result<Joint> {
        let dim = 9 + 6 * n;
        let (mut h, mut g) = (DMatrix::zeros(dim, dim), DVector::zeros(dim));
        let mut loss = 0.0;
        for v in 0..n {
            let e = eta.rows(6 * v, 6);
            let (r, t) = corrected(&cams[v], e.as_slice());
            objectives[v].set_extrinsics(0, r, t);
            if wn[v] == 0.0 {
                continue;
            }
            let (ev, ne) = objectives[v].normal_equations(model, pose)?;
            loss += wn[v] * ev.total;
            let hv = DMatrix::from_fn(9, 9, |i, j| ne.jtj[(i, j)]) * wn[v];
            let gv = DVector::from_fn(9, |i, _| ne.jtr[i]) * wn[v];
            let kv = pose_of_twist(pose, r, -(r.transpose() * t));
            let hk = &hv * &kv;
            h.view_mut((0, 0), (9, 9)).add_assign(&hv);
            h.view_mut((0, 9 + 6 * v), (9, 6)).add_assign(&hk);
            h.view_mut((9 + 6 * v, 0), (6, 9)).add_assign(&hk.transpose());
            h.view_mut((9 + 6 * v, 9 + 6 * v), (6, 6))
                .add_assign(&(kv.transpose() * &hk));
            g.rows_mut(0, 9).add_assign(&gv);
            g.rows_mut(9 + 6 * v, 6).add_assign(&(kv.transpose() * &gv));
        }
        if temperature.is_nan() {
            // T = tr(H Σ)/k over the free directions (module doc).
            let hp = p.transpose() * h.view((0, 0), (9, 9)) * &p;
            let pinv = (p.transpose() * &p)
                .try_inverse()
                .unwrap_or_else(|| DMatrix::identity(k, k))
                * p.transpose();
            let sp = &pinv * DMatrix::from_fn(9, 9, |i, j| pose_covariance[(i, j)]) * pinv.transpose();
            *temperature = ((hp * sp).trace() / k as f64).max(0.0);
        }
        let t = *temperature;
        let mut prior_cost = 0.0;
        for v in 0..n {
            for i in 0..6 {
                let (q, x) = (precision[v][i], eta[6 * v + i]);
                prior_cost += 0.5 * t * q * x * x;
                h[(9 + 6 * v + i, 9 + 6 * v + i)] += t * q;
                g[9 + 6 * v + i] += t * q * x;
            }
        }
        let h_pose = p.transpose() * h.view((0, 0), (9, 9)) * &p;
        Ok(Joint {
            cost: loss + prior_cost,
            h: basis.transpose() * &h * &basis,
            g: basis.transpose() * g,
            h_pose,
        })
    };

    // The one LM loop (`crate::optim::lm`) over points (pose, η).
    let mut point = (pose, DVector::zeros(6 * n));
    let first = evaluate(&point.0, &point.1, &mut temperature)?;
    if !(temperature.is_finite() && temperature > 0.0) {
        return Err(Error::Settings(
            "camera correction: the pose's uncertainty gives no temperature".into(),
        ));
    }
    let start_cost = first.cost;
    let step = |(pose, eta): &(Pose, DVector<f64>), d: &DVector<f64>| {
        let full = &basis * d;
        let next_pose = pose.perturbed(&Vec9::from_fn(|i, _| full[i]));
        let next_eta = eta + full.rows(9, 6 * n);
        (next_pose.validate().is_ok() && next_eta.iter().all(|v| v.is_finite())).then_some((next_pose, next_eta))
    };
    let mut lm = Lm::new();
    let mut current = first;
    for i in 0..ITERATIONS {
        point = lm.next(point, current.cost, current.h, current.g, step);
        if lm.stalled() || i + 1 == ITERATIONS {
            break;
        }
        current = evaluate(&point.0, &point.1, &mut temperature)?;
    }
    // The best point; its evaluation leaves the objectives' cameras as the final
    // corrections are (for the figures), and gives its model for the covariance.
    let (pose, eta) = lm.best().map(|(p, _)| p.clone()).unwrap_or(point);
    let current = evaluate(&pose, &eta, &mut temperature)?;

    // The covariance the cameras' freedom adds: T·([H⁻¹]_θθ − H_θθ⁻¹), free directions.
    let extra = {
        let hi = crate::uncertainty::ridge_inverse(&current.h)?;
        let joint = hi.view((0, 0), (k, k)).into_owned();
        let alone = crate::uncertainty::ridge_inverse(&current.h_pose)?;
        let d = (joint - alone) * temperature;
        let sym = (&d + d.transpose()) * 0.5;
        let e = sym.symmetric_eigen();
        let clipped =
            &e.eigenvectors * DMatrix::from_diagonal(&e.eigenvalues.map(|v| v.max(0.0))) * e.eigenvectors.transpose();
        let full = &p * clipped * p.transpose();
        Mat9::from_fn(|i, j| full[(i, j)])
    };
    let mut out_views = Vec::with_capacity(n);
    let mut corrections = Vec::with_capacity(n);
    for (v, view) in views.iter().enumerate() {
        let e = eta.rows(6 * v, 6);
        let (r, t) = corrected(&cams[v], e.as_slice());
        let corrected_view = view.with_extrinsics(r, t);
        let phi = DVec3::new(e[0], e[1], e[2]);
        let rho = DVec3::new(e[3], e[4], e[5]);
        let distance = cams[v].centre().distance(centre).max(f64::MIN_POSITIVE);
        corrections.push(CameraCorrection {
            view: view.name().to_string(),
            rotation_deg: (phi * 180.0 / std::f64::consts::PI).to_array(),
            translation: rho.to_array(),
            angle_deg: phi.length().to_degrees(),
            shift_pct: 100.0 * rho.length() / distance,
            world_to_camera: mat4_to_rows(corrected_view.camera().world_to_camera_matrix()),
        });
        out_views.push(corrected_view);
    }
    let loss_reduction = if start_cost > 0.0 {
        ((start_cost - current.cost) / start_cost).max(0.0)
    } else {
        0.0
    };
    Ok(Refined {
        pose,
        views: out_views,
        corrections,
        extra_covariance: extra,
        test: CameraTest {
            loss_reduction,
            min_reduction: prior.min_reduction,
            applied: loss_reduction >= prior.min_reduction,
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_camera_twist_moves_the_image_as_the_equivalent_pose_change_does() {
        // K_v against finite differences: a small camera twist and the pose change
        // K_v·η project every model point to the same pixels.
        let pose = Pose {
            rotation: so3::exp(DVec3::new(0.3, -0.2, 0.5)),
            translation: DVec3::new(0.1, 0.2, -0.1),
            scale: DVec3::new(1.1, 0.9, 1.0),
        };
        let cam = Camera::look_at(DVec3::new(0.5, -0.4, -3.0), DVec3::ZERO, DVec3::Y, 64, 48, 60.0);
        let k = pose_of_twist(&pose, cam.rotation, cam.centre());
        let pts = [
            DVec3::new(0.2, 0.1, -0.3),
            DVec3::new(-0.4, 0.3, 0.2),
            DVec3::new(0.0, -0.5, 0.1),
        ];
        for j in 0..6 {
            // Central differences of the projected points under ±h of twist j and of
            // the pose change ±h·K_v e_j.
            let h = 1e-5;
            let project = |sign: f64| {
                let mut eta = [0.0; 6];
                eta[j] = sign * h;
                let (r, t) = corrected(&cam, &eta);
                let moved_cam = Camera {
                    rotation: r,
                    translation: t,
                    ..cam
                };
                let d = Vec9::from_fn(|i, _| sign * k[(i, j)] * h);
                let moved_pose = pose.perturbed(&d);
                pts.map(|p| {
                    (
                        moved_cam.project(moved_cam.to_camera(pose.apply(p))),
                        cam.project(cam.to_camera(moved_pose.apply(p))),
                    )
                })
            };
            let (plus, minus) = (project(1.0), project(-1.0));
            for i in 0..pts.len() {
                let twist = (plus[i].0 - minus[i].0) / (2.0 * h);
                let pose_change = (plus[i].1 - minus[i].1) / (2.0 * h);
                assert!(twist.length() > 1.0, "twist {j} moves point {i}");
                assert!(
                    (twist - pose_change).length() < 1e-5 * twist.length(),
                    "twist {j}, point {i}: {twist:?} vs {pose_change:?}"
                );
            }
        }
    }

    #[test]
    fn the_gauge_basis_spans_what_keeps_the_mean_world_motion_zero() {
        let cams = [
            Camera::look_at(DVec3::new(0.0, 0.0, -3.0), DVec3::ZERO, DVec3::Y, 64, 48, 60.0),
            Camera::look_at(DVec3::new(3.0, 0.5, 0.0), DVec3::ZERO, DVec3::Y, 64, 48, 60.0),
            Camera::look_at(DVec3::new(0.0, 2.5, 2.0), DVec3::ZERO, DVec3::Y, 64, 48, 60.0),
        ];
        let b = gauge_basis(&cams);
        assert_eq!((b.nrows(), b.ncols()), (18, 12));
        assert!(((b.transpose() * &b) - DMatrix::identity(12, 12)).abs().max() < 1e-9);
        // Every basis correction keeps the mean world motion zero…
        assert!((world_twists(&cams) * &b).abs().max() < 1e-9);
        // …and the common motion (every camera moved by the same world twist: the
        // gauge) is not in their span.
        let w = [0.01, -0.02, 0.005, 0.1, 0.0, -0.05];
        let mut common = DVector::zeros(18);
        for (v, cam) in cams.iter().enumerate() {
            // η_v = A_v⁻¹ w: φ = R_c a, ρ = R_c (b − c × a).
            let a = DVec3::new(w[0], w[1], w[2]);
            let bb = DVec3::new(w[3], w[4], w[5]);
            let phi = cam.rotation * a;
            let rho = cam.rotation * (bb - cam.centre().cross(a));
            for i in 0..3 {
                common[6 * v + i] = phi[i];
                common[6 * v + 3 + i] = rho[i];
            }
        }
        let rest = &common - &b * (b.transpose() * &common);
        assert!(
            rest.norm() > 0.3 * common.norm(),
            "{} of {}",
            rest.norm(),
            common.norm()
        );
        // It moves every camera alike: its world twists sum to 3w.
        let sum = world_twists(&cams) * &common;
        for i in 0..6 {
            assert!((sum[i] - 3.0 * w[i]).abs() < 1e-12);
        }
    }
}
