//! How sure the pose is: the pose covariance at the optimum, 9×9 in
//! `[ω, t, log s]` (ω the right tangent, `R_true ≈ R·exp([ω]×)`; t in scene units),
//! and the standard deviations a reader wants (degrees about each model axis,
//! translation, scale in %, the predicted ADD spread).
//!
//! **The noise model.** A mask is the object's true silhouette with its boundary
//! displaced along the normal by `ν(s)` pixels (segmentation error, quantisation,
//! resampling), ν correlated along the contour. Near the optimum the model's outline
//! moves along its normal by `g(s)ᵀδθ` (`g` the outline's normal velocity per unit θ,
//! [`outline`]), so the fit is, to first order, the least-squares fit of `gᵀδθ` to the
//! boundary displacement over every view's outline:
//!
//! ```text
//! H = Σ_v w_v ∮ g gᵀ ds   (the Gauss–Newton normal matrix of the outline)
//! δθ = H⁻¹ Σ_v w_v ∮ g ν ds
//! ```
//!
//! ν is correlated along the contour, so its variance cannot be assumed per pixel.
//! It is measured at the optimum, per view, from the residual displacement `n(s)` (the
//! mask contour's signed distance at the model's outline): its variance per unit of
//! outline `σ² = ∮ n² ds / ∮ ds` and its integral correlation length `λ` (a kernel
//! estimate over sample pairs closer than [`NoiseModel::bandwidth_px`],
//! [`outline::correlation_length`]). When λ is short against the outline's features,
//! `∮∮ g(s) E[ν(s)ν(s')] g(s')ᵀ ds ds' ≈ σ²λ·∮ g gᵀ ds`, so
//!
//! ```text
//! Σ = κ · H⁻¹ (Σ_v w_v² max(σ_v²λ_v, floor) H_v) H⁻¹
//! ```
//!
//! (a cluster-robust sandwich over cells of the outline was tried first: with 2–4 views
//! there are too few cells for the 9 parameters and, since the residuals at the optimum
//! are orthogonal to the score, it under-reports the spread badly — 71 % coverage).
//! κ ([`NoiseModel::inflation`]) absorbs what the model leaves out — the fit
//! minimises IoU + contour, not this least-squares form; the residual's shrinkage at
//! the optimum; correlation at the scale of the object — and is *calibrated*: chosen
//! on one set of synthetic scenes with known truth so that the truth falls inside the
//! 95 % ellipsoid in about 95 % of them, then checked on other scenes (docs/benchmark-history.md
//! "Uncertainty"; `tests/tier2/uncertainty.rs` prints the coverage). The floor
//! is the pixel quantisation of an ideal mask (`1/12 px²` over a correlation of 1 px),
//! so a perfect fit to a perfect mask still reports the grid's uncertainty.
//!
//! Directions the views do not constrain (rotation about a symmetry axis, depth from
//! one view) get a very large variance rather than a fake certainty: H is inverted
//! with a ridge of 1e-9 of its mean eigenvalue.

pub mod fit;
pub mod next_view;
pub mod outline;

use crate::error::{Error, Result};
use crate::mesh::Mesh;
use crate::optim::params::ScaleMode;
use crate::pose::Pose;
use crate::so3;
use glam::DVec3;
use nalgebra::{DMatrix, SMatrix};
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use serde::{Deserialize, Serialize};

pub use fit::fit_uncertainty;
pub use next_view::{candidate_viewpoints, rank_views, RankedView, Viewpoints};
pub use outline::{outline_information, view_information, ViewInformation};

pub use crate::pose::{Mat9, Vec9, POSE_DIM as DIM};

/// The ridge of the inverse of H, relative to its mean eigenvalue.
const RIDGE: f64 = 1e-9;

/// χ²(9) at 0.95: the squared Mahalanobis radius of the 95 % ellipsoid.
pub const CHI2_9_95: f64 = 16.919;

/// How residuals become a covariance (module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NoiseModel {
    /// Bandwidth of the residual's correlation estimate, canvas pixels.
    pub bandwidth_px: f64,
    /// κ, the calibrated inflation of the sandwich.
    pub inflation: f64,
    /// Floor of the noise power σ²λ, px³ (quantisation of an ideal mask).
    pub floor_px3: f64,
    /// Spacing of the outline samples, pixels.
    pub spacing_px: f64,
}

impl Default for NoiseModel {
    /// A bandwidth of 24 px, κ = 2.2 (calibrated: docs/benchmark-history.md "Uncertainty"), the
    /// quantisation floor 1/12 px³, samples every ½ px.
    fn default() -> Self {
        NoiseModel {
            bandwidth_px: 24.0,
            inflation: 2.2,
            floor_px3: 1.0 / 12.0,
            spacing_px: 0.5,
        }
    }
}

/// Readable standard deviations of a pose covariance.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StdDev {
    /// About each model axis, degrees.
    pub rotation_deg: [f64; 3],
    /// Translation, scene units (world axes).
    pub translation: [f64; 3],
    /// Scale along each model axis, % (of the scale).
    pub scale_pct: [f64; 3],
    /// The ADD (mean model-point displacement) expected from the covariance, scene units.
    pub add_mean: f64,
    /// The ADD within which the truth lies with 95 % confidence: the 95th percentile of
    /// the ADD of poses drawn from the covariance ([`StdDev::add_95_alone`]) — or, when
    /// the fit has alternatives (`ambiguous`), the larger bound that reaches each
    /// alternative's own: a mixture, not one Gaussian.
    pub add_95: f64,
    /// The 95th percentile from this pose's covariance alone.
    #[serde(default)]
    pub add_95_alone: f64,
    /// The object's diameter at the pose (scale applied), scene units: `add_95 /
    /// diameter` is comparable with the ADD threshold of 10 % of the diameter.
    pub diameter: f64,
    /// The RMS distance between the model's outline and the masks' contours at the
    /// optimum, canvas pixels (what the covariance was measured from).
    pub boundary_rms_px: f64,
}

/// The covariance and its readable form, with the parts it was made of (for
/// predicting what another view would add, [`next_view`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Uncertainty {
    /// 9×9 in `[ω (rad), t (scene units), log s]`.
    pub covariance: Mat9,
    /// Its standard deviations.
    pub std_dev: StdDev,
    /// `H = Σ_v w_v H_v`, the outline's normal matrix over the views.
    pub information: Mat9,
    /// `Σ_v w_v² max(σ_v²λ_v, floor) H_v`, the noise the views' outlines carry.
    pub noise: Mat9,
    /// The views' mean noise power σ²λ (px³), weighted by their information: what a
    /// further photograph of the same kind is expected to carry.
    pub noise_power: f64,
    /// The parameters the fit freed.
    pub mode: ScaleMode,
}

impl Uncertainty {
    /// The covariance as row-major rows.
    pub fn covariance_rows(&self) -> [[f64; DIM]; DIM] {
        std::array::from_fn(|i| std::array::from_fn(|j| self.covariance[(i, j)]))
    }
}

/// Inverts a symmetric positive semi-definite matrix with a ridge of 1e-9 of its mean
/// eigenvalue (so unconstrained directions get a very large, finite variance).
pub fn ridge_inverse(h: &DMatrix<f64>) -> Result<DMatrix<f64>> {
    let n = h.nrows();
    let mean = h.trace() / n.max(1) as f64;
    if !(mean.is_finite() && mean > 0.0) {
        return Err(Error::Settings("uncertainty: the outline constrains nothing".into()));
    }
    let sym = (h + h.transpose()) * 0.5 + DMatrix::identity(n, n) * (RIDGE * mean);
    sym.cholesky()
        .map(|c| c.inverse())
        .ok_or_else(|| Error::Settings("uncertainty: the normal matrix is not positive definite".into()))
}

/// The views' information summed: `(H, B, mean noise power)` with each view weighted
/// by `weights` (the fit's robust weights; module doc).
///
/// Errors: mismatched lengths.
pub fn combine(infos: &[ViewInformation], weights: &[f64], noise: &NoiseModel) -> Result<(Mat9, Mat9, f64)> {
    if infos.len() != weights.len() {
        return Err(Error::Settings(format!(
            "uncertainty: {} views but {} weights",
            infos.len(),
            weights.len()
        )));
    }
    let (mut h, mut b, mut tr) = (Mat9::zeros(), Mat9::zeros(), 0.0);
    for (info, &w) in infos.iter().zip(weights) {
        h += info.h * w;
        b += info.h * (info.noise_power().max(noise.floor_px3) * w * w);
        tr += info.h.trace() * w * w;
    }
    let power = if tr > 0.0 { b.trace() / tr } else { noise.floor_px3 };
    Ok((h, b, power))
}

/// The sandwich `κ·H⁻¹BH⁻¹` over the directions `mode` frees (module doc).
///
/// Errors: H constrains nothing.
pub fn sandwich(h: &Mat9, b: &Mat9, mode: ScaleMode, noise: &NoiseModel) -> Result<Mat9> {
    let p = mode.basis();
    let hp = p.transpose() * to_dyn(h) * &p;
    let k = hp.nrows();
    // The ridge is a weak observation of every direction, with the views' mean noise:
    // a direction no view constrains gets a variance 10⁹ times that of a constrained one
    // (not the zero that `H⁻¹BH⁻¹` alone would give it, since B vanishes there too).
    let ridge = RIDGE * hp.trace() / k.max(1) as f64;
    let power = if h.trace() > 0.0 { b.trace() / h.trace() } else { 0.0 };
    let bp = p.transpose() * to_dyn(b) * &p + DMatrix::identity(k, k) * (power * ridge);
    let hi = ridge_inverse(&hp)?;
    let cov = &p * (&hi * bp * &hi) * p.transpose() * noise.inflation;
    Ok(Mat9::from_fn(|i, j| 0.5 * (cov[(i, j)] + cov[(j, i)])))
}

fn to_dyn(m: &Mat9) -> DMatrix<f64> {
    DMatrix::from_fn(DIM, DIM, |i, j| m[(i, j)])
}

/// The error of `fitted` against `truth` in the covariance's coordinates:
/// `[log(R̂ᵀR), t − t̂, log(s/ŝ)]`, so that `truth ≈ fitted.perturbed(e)`.
pub fn pose_error(fitted: &Pose, truth: &Pose) -> Vec9 {
    let w = so3::log(fitted.rotation.transpose() * truth.rotation);
    let t = truth.translation - fitted.translation;
    let s = (truth.scale / fitted.scale).to_array().map(f64::ln);
    Vec9::from_column_slice(&[w.x, w.y, w.z, t.x, t.y, t.z, s[0], s[1], s[2]])
}

/// `eᵀΣ⁻¹e` over the directions `mode` frees (the others' errors are not the fit's).
///
/// Errors: a singular covariance.
pub fn mahalanobis_sq(cov: &Mat9, e: &Vec9, mode: ScaleMode) -> Result<f64> {
    let p = mode.basis();
    // Σ = P·Σ_free·Pᵀ, so Σ_free = P⁺ΣP⁺ᵀ and e's free coordinates are P⁺e.
    let pinv = (p.transpose() * &p)
        .try_inverse()
        .map(|m| m * p.transpose())
        .ok_or_else(|| Error::Settings("uncertainty: bad basis".into()))?;
    let cp = &pinv * to_dyn(cov) * pinv.transpose();
    let ep = &pinv * DMatrix::from_column_slice(DIM, 1, e.as_slice());
    let ci = ridge_inverse(&cp)?;
    Ok((ep.transpose() * ci * &ep)[(0, 0)])
}

/// Model points the ADD figures use: at most `max` vertices, evenly strided.
fn add_points(mesh: &Mesh, max: usize) -> Vec<DVec3> {
    let n = mesh.positions.len();
    let stride = n.div_ceil(max.max(1)).max(1);
    mesh.positions.iter().step_by(stride).copied().collect()
}

/// The readable standard deviations of `cov` at `pose`; the ADD figures from 512
/// poses drawn from the covariance (a fixed seed: the same figures every time).
pub fn std_dev(mesh: &Mesh, pose: &Pose, cov: &Mat9, boundary_rms_px: f64) -> StdDev {
    let sd = |i: usize| cov[(i, i)].max(0.0).sqrt();
    let points = add_points(mesh, 1000);
    let (mean, p95) = sampled_add(&points, pose, cov, 512);
    let posed = Mesh {
        positions: mesh.positions.iter().map(|&p| pose.apply(p)).collect(),
        triangles: mesh.triangles.clone(),
    };
    StdDev {
        diameter: posed.diameter(),
        rotation_deg: [0, 1, 2].map(|i| sd(i).to_degrees()),
        translation: [3, 4, 5].map(sd),
        scale_pct: [6, 7, 8].map(|i| 100.0 * sd(i)),
        add_mean: mean,
        add_95: p95,
        add_95_alone: p95,
        boundary_rms_px,
    }
}

/// Mean and 95th percentile of the ADD of poses drawn from N(pose, cov).
fn sampled_add(points: &[DVec3], pose: &Pose, cov: &Mat9, n: usize) -> (f64, f64) {
    let Some(l) = psd_factor(cov) else {
        return (f64::NAN, f64::NAN);
    };
    let mut rng = SmallRng::seed_from_u64(0x5eed_add5);
    let base: Vec<DVec3> = points.iter().map(|&p| pose.apply(p)).collect();
    let mut adds: Vec<f64> = (0..n)
        .map(|_| {
            let z = Vec9::from_fn(|_, _| normal(&mut rng));
            let q = pose.perturbed(&(l * z));
            points
                .iter()
                .zip(&base)
                .map(|(&p, b)| (q.apply(p) - *b).length())
                .sum::<f64>()
                / points.len().max(1) as f64
        })
        .collect();
    adds.sort_by(f64::total_cmp);
    let mean = adds.iter().sum::<f64>() / n.max(1) as f64;
    (mean, adds[(n * 95 / 100).min(n - 1)])
}

/// `count` poses drawn from N(pose, cov) — the 3D view's ghosts: `pose.perturbed(L·z)`,
/// z standard normal from a generator seeded with `seed` (the same ghosts every time),
/// L a factor of the covariance (symmetrised) in `[ω (right tangent, R·exp([ω]×)), t,
/// log s]`. A semi-definite covariance draws in its range only (a zero covariance gives
/// `pose` itself); an indefinite one has its negative eigenvalues clipped to zero.
///
/// Errors: a covariance holding a non-finite number.
pub fn ghost_poses(pose: &Pose, cov: &Mat9, count: usize, seed: u64) -> Result<Vec<Pose>> {
    let sym = (cov + cov.transpose()) * 0.5;
    let l = psd_factor(&sym)
        .ok_or_else(|| Error::Settings("ghost poses: the covariance holds a number that is not finite".into()))?;
    let mut rng = SmallRng::seed_from_u64(seed);
    Ok((0..count)
        .map(|_| {
            let z = Vec9::from_fn(|_, _| normal(&mut rng));
            pose.perturbed(&(l * z))
        })
        .collect())
}

/// A 9×9 covariance from its rows (as the result file writes it).
///
/// Errors: not 9 rows of 9 numbers.
pub fn mat9_from_rows(rows: &[Vec<f64>]) -> Result<Mat9> {
    if rows.len() != DIM || rows.iter().any(|r| r.len() != DIM) {
        let shape: Vec<usize> = rows.iter().map(Vec::len).collect();
        return Err(Error::Settings(format!(
            "a pose covariance is 9×9 in [ω, t, log s], got {} rows of {shape:?} numbers",
            rows.len()
        )));
    }
    Ok(Mat9::from_fn(|i, j| rows[i][j]))
}

/// A factor L with `L Lᵀ = cov` (eigen-decomposition; negative round-off clipped).
fn psd_factor(cov: &Mat9) -> Option<Mat9> {
    if !cov.iter().all(|v| v.is_finite()) {
        return None;
    }
    let e = cov.symmetric_eigen();
    let sqrt = e.eigenvalues.map(|v| v.max(0.0).sqrt());
    Some(e.eigenvectors * Mat9::from_diagonal(&sqrt))
}

/// A standard normal deviate (Box–Muller).
fn normal(rng: &mut SmallRng) -> f64 {
    let u: f64 = rng.gen_range(f64::MIN_POSITIVE..1.0);
    let v: f64 = rng.gen();
    (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
}

/// The ADD metric: `W = mean_i J_iᵀJ_i`, J_i = ∂(model point i in the world)/∂θ, so
/// that `δθᵀWδθ` is the mean squared point displacement and `tr(WΣ)` its expectation.
pub fn add_metric(mesh: &Mesh, pose: &Pose) -> Mat9 {
    let points = add_points(mesh, 1000);
    let mut w = Mat9::zeros();
    for p in &points {
        let y = pose.scale * *p;
        // ∂/∂ω: R[e×]y = R(e × y); ∂/∂t: I; ∂/∂ls_k: R e_k y_k.
        let mut j = SMatrix::<f64, 3, DIM>::zeros();
        for k in 0..3 {
            let mut e = DVec3::ZERO;
            e[k] = 1.0;
            let cols = [pose.rotation * e.cross(y), e, pose.rotation * (e * y)];
            for (g, c) in cols.iter().enumerate() {
                for r in 0..3 {
                    j[(r, 3 * g + k)] = c[r];
                }
            }
        }
        w += j.transpose() * j;
    }
    w / points.len().max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pose_error_inverts_perturb() {
        let pose = Pose {
            rotation: so3::exp(DVec3::new(0.3, -0.2, 0.9)),
            translation: DVec3::new(0.1, 2.0, -1.0),
            scale: DVec3::new(1.2, 0.8, 1.0),
        };
        let d = Vec9::from_column_slice(&[0.01, -0.02, 0.005, 0.1, -0.05, 0.02, 0.01, -0.03, 0.02]);
        let e = pose_error(&pose, &pose.perturbed(&d));
        assert!((e - d).norm() < 1e-12, "{e} vs {d}");
    }

    #[test]
    fn the_add_metric_gives_the_mean_squared_displacement_of_a_small_move() {
        let mesh = crate::app::synth::blob_mesh(4, 6);
        let pose = Pose {
            rotation: so3::exp(DVec3::new(0.3, -0.2, 0.9)),
            translation: DVec3::new(0.1, 2.0, -1.0),
            scale: DVec3::new(1.2, 0.8, 1.0),
        };
        let w = add_metric(&mesh, &pose);
        let d = Vec9::from_column_slice(&[1e-4, -2e-4, 5e-5, 1e-4, -5e-5, 2e-5, 1e-4, -3e-4, 2e-4]);
        let q = pose.perturbed(&d);
        let pts = add_points(&mesh, 1000);
        let msd = pts
            .iter()
            .map(|&p| (q.apply(p) - pose.apply(p)).length_squared())
            .sum::<f64>()
            / pts.len() as f64;
        let pred = (d.transpose() * w * d)[(0, 0)];
        assert!((msd / pred - 1.0).abs() < 1e-3, "{msd} vs {pred}");
    }

    #[test]
    fn sampled_add_grows_with_the_covariance_and_the_mahalanobis_radius_is_chi_square() {
        let mesh = crate::app::synth::blob_mesh(4, 6);
        let pose = Pose::IDENTITY;
        let cov = Mat9::from_diagonal(&Vec9::from_column_slice(&[
            1e-4, 1e-4, 1e-4, 1e-4, 1e-4, 1e-4, 1e-4, 1e-4, 1e-4,
        ]));
        let small = std_dev(&mesh, &pose, &cov, 0.3);
        let big = std_dev(&mesh, &pose, &(cov * 4.0), 0.3);
        assert!((big.add_mean / small.add_mean - 2.0).abs() < 0.05, "{small:?} {big:?}");
        assert!(small.add_95 > small.add_mean);
        assert!((small.rotation_deg[0] - 0.01f64.to_degrees()).abs() < 1e-9);
        assert!((small.scale_pct[2] - 1.0).abs() < 1e-9);
        // e = 2σ along one axis: d² = 4.
        let e = Vec9::from_column_slice(&[0.0, 0.02, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
        let d2 = mahalanobis_sq(&cov, &e, ScaleMode::Anisotropic).unwrap();
        assert!((d2 - 4.0).abs() < 1e-6, "{d2}");
        // With a uniform scale only the shared log-scale counts.
        let iso = covariance_of_iso();
        let e = Vec9::from_column_slice(&[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.01, 0.01, 0.01]);
        let d2 = mahalanobis_sq(&iso, &e, ScaleMode::Isotropic).unwrap();
        assert!((d2 - 1.0).abs() < 1e-6, "{d2}");
    }

    fn some_pose() -> Pose {
        Pose {
            rotation: so3::exp(DVec3::new(0.3, -0.2, 0.9)),
            translation: DVec3::new(0.1, 2.0, -1.0),
            scale: DVec3::new(1.2, 0.8, 1.0),
        }
    }

    /// The sample covariance of the ghosts' coordinates `[ω, t, log s]` about `pose`.
    fn sample_covariance(pose: &Pose, ghosts: &[Pose]) -> Mat9 {
        let e: Vec<Vec9> = ghosts.iter().map(|g| pose_error(pose, g)).collect();
        let n = e.len() as f64;
        let mean = e.iter().sum::<Vec9>() / n;
        e.iter().map(|x| (x - mean) * (x - mean).transpose()).sum::<Mat9>() / (n - 1.0)
    }

    #[test]
    fn ghosts_of_a_zero_covariance_are_the_pose() {
        let pose = some_pose();
        let ghosts = ghost_poses(&pose, &Mat9::zeros(), 5, 1).unwrap();
        assert_eq!(ghosts.len(), 5);
        for g in &ghosts {
            assert!(g.rotation.abs_diff_eq(pose.rotation, 1e-12), "{g:?}");
            assert_eq!(g.translation, pose.translation);
            assert_eq!(g.scale, pose.scale);
        }
        assert!(ghost_poses(&pose, &Mat9::zeros(), 0, 1).unwrap().is_empty());
    }

    #[test]
    fn ghosts_follow_the_covariance_and_the_seed() {
        let pose = some_pose();
        // Correlated: σ 0.05 rad, 0.01 units, 2 % in scale; ω_x with t_y, t_x with ls_z.
        let sd = [0.05, 0.04, 0.03, 0.01, 0.012, 0.008, 0.02, 0.015, 0.01];
        let mut cov = Mat9::from_fn(|i, j| if i == j { sd[i] * sd[j] } else { 0.0 });
        for (i, j, r) in [(0, 4, 0.6), (3, 8, -0.5), (6, 7, 0.3)] {
            cov[(i, j)] = r * sd[i] * sd[j];
            cov[(j, i)] = cov[(i, j)];
        }
        let n = 20_000;
        let ghosts = ghost_poses(&pose, &cov, n, 7).unwrap();
        let s = sample_covariance(&pose, &ghosts);
        for i in 0..DIM {
            for j in 0..DIM {
                // The sample covariance's standard error, five times.
                let se = ((cov[(i, i)] * cov[(j, j)] + cov[(i, j)].powi(2)) / n as f64).sqrt();
                assert!(
                    (s[(i, j)] - cov[(i, j)]).abs() < 5.0 * se,
                    "({i}, {j}): sample {} vs {}",
                    s[(i, j)],
                    cov[(i, j)]
                );
            }
        }
        // Seeded: the same ghosts again; another seed, others.
        assert_eq!(ghost_poses(&pose, &cov, 3, 7).unwrap(), ghosts[..3].to_vec());
        assert_ne!(ghost_poses(&pose, &cov, 3, 8).unwrap(), ghosts[..3].to_vec());
    }

    #[test]
    fn singular_and_indefinite_covariances_give_finite_ghosts() {
        let pose = some_pose();
        // Singular: only t_x uncertain; the ghosts move along x only.
        let mut singular = Mat9::zeros();
        singular[(3, 3)] = 1e-4;
        let ghosts = ghost_poses(&pose, &singular, 12, 1).unwrap();
        for g in &ghosts {
            let e = pose_error(&pose, g);
            assert!(e.iter().all(|v| v.is_finite()));
            for k in (0..DIM).filter(|&k| k != 3) {
                assert!(e[k].abs() < 1e-12, "coordinate {k} moved: {e}");
            }
        }
        assert!(ghosts
            .iter()
            .any(|g| (g.translation.x - pose.translation.x).abs() > 1e-3));
        // Indefinite (a negative eigenvalue): clipped to the nearest semi-definite matrix.
        let mut indefinite = Mat9::identity() * 1e-4;
        indefinite[(3, 4)] = 2e-4;
        indefinite[(4, 3)] = 2e-4;
        assert!(indefinite.symmetric_eigen().eigenvalues.min() < 0.0);
        let ghosts = ghost_poses(&pose, &indefinite, 2000, 1).unwrap();
        assert!(ghosts.iter().all(|g| g.matrix().is_finite()));
        // Along (1, −1)/√2 in (t_x, t_y) the eigenvalue −1e-4 is clipped: no spread there.
        let along: Vec<f64> = ghosts
            .iter()
            .map(|g| (g.translation.x - pose.translation.x) - (g.translation.y - pose.translation.y))
            .collect();
        assert!(along.iter().all(|v| v.abs() < 1e-12), "{:?}", &along[..3]);
    }

    #[test]
    fn a_covariance_that_is_not_finite_or_not_9_by_9_is_an_error() {
        let mut cov = Mat9::identity() * 1e-4;
        cov[(2, 5)] = f64::NAN;
        assert!(ghost_poses(&Pose::IDENTITY, &cov, 12, 1).is_err());
        cov[(2, 5)] = f64::INFINITY;
        assert!(ghost_poses(&Pose::IDENTITY, &cov, 12, 1).is_err());
        assert!(mat9_from_rows(&[vec![1.0, 0.0], vec![0.0, 1.0]]).is_err());
        let mut rows = vec![vec![0.0; 9]; 9];
        rows[8].pop();
        assert!(mat9_from_rows(&rows).is_err());
        rows[8].push(0.5);
        assert_eq!(mat9_from_rows(&rows).unwrap()[(8, 8)], 0.5);
    }

    fn covariance_of_iso() -> Mat9 {
        // Shared log-scale with σ = 0.01; everything else σ = 0.01 too.
        let mut c = Mat9::identity() * 1e-4;
        for i in 6..9 {
            for j in 6..9 {
                c[(i, j)] = 1e-4;
            }
        }
        c
    }
}
