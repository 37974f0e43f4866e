//! The optimiser's parameters: a 9-vector of increments applied to the current pose,
//! `R ← R·exp([ω]×)`, `t ← t + L·τ`, `s ← s ⊙ exp(ℓ)`, where L is the object's
//! radius in the world (so one step size serves any object size, unit and camera
//! distance). Order: [ω0, ω1, ω2, τ0, τ1, τ2, ℓ0, ℓ1, ℓ2]. [`ScaleMode`] says which of
//! them move: its [`ScaleMode::basis`] is the one free-parameter basis of the crate
//! (the optimisers, the uncertainty and the camera correction all use it).

use crate::pose::{Pose, Vec9, POSE_DIM};
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

/// How the scale is fitted: which pose parameters are free.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ScaleMode {
    /// Per-axis scale (9-DoF; the default).
    Anisotropic,
    /// One scale for all axes (7-DoF).
    Isotropic,
    /// The CAD model is to scale: the scale stays at the initial value (1 unless an
    /// initial pose gives another), in the search and every stage (6-DoF).
    Fixed,
}

impl ScaleMode {
    /// The free directions of `[ω, t, log s]` as the columns of a 9×k matrix: the unit
    /// vectors of rotation and translation, then each log-scale axis (anisotropic), their
    /// sum (isotropic) or nothing (fixed).
    pub fn basis(self) -> DMatrix<f64> {
        let k = match self {
            ScaleMode::Anisotropic => 9,
            ScaleMode::Isotropic => 7,
            ScaleMode::Fixed => 6,
        };
        let mut p = DMatrix::zeros(POSE_DIM, k);
        for i in 0..6 {
            p[(i, i)] = 1.0;
        }
        match self {
            ScaleMode::Anisotropic => (6..9).for_each(|i| p[(i, i)] = 1.0),
            ScaleMode::Isotropic => (6..9).for_each(|i| p[(i, 6)] = 1.0),
            ScaleMode::Fixed => {}
        }
        p
    }

    /// Whether the scale moves at all (the search re-fits it unless fixed).
    pub fn fits_scale(self) -> bool {
        self != ScaleMode::Fixed
    }

    /// A 9-vector (gradient or step) restricted to the free directions: the scale part
    /// zeroed (fixed) or replaced by its mean (isotropic).
    pub fn restrict(self, d: &mut [f64; POSE_DIM]) {
        match self {
            ScaleMode::Anisotropic => {}
            ScaleMode::Isotropic => {
                let m = (d[6] + d[7] + d[8]) / 3.0;
                d[6..9].iter_mut().for_each(|v| *v = m);
            }
            ScaleMode::Fixed => d[6..9].iter_mut().for_each(|v| *v = 0.0),
        }
    }
}

/// The factor of each parameter between pose units `[ω, t, log s]` and the scaled
/// parameters `[ω, τ, ℓ]`: `length` for the translation, 1 otherwise.
pub fn unit(i: usize, length: f64) -> f64 {
    if (3..6).contains(&i) {
        length
    } else {
        1.0
    }
}

/// Converts a gradient in pose units [ω, t, log s] into the scaled parameters [ω, τ, ℓ].
pub fn scale_gradient(g: &[f64; POSE_DIM], length: f64) -> [f64; POSE_DIM] {
    std::array::from_fn(|i| g[i] * unit(i, length))
}

/// Applies a scaled increment to a pose.
pub fn apply(pose: &Pose, d: &[f64; POSE_DIM], length: f64) -> Pose {
    pose.perturbed(&Vec9::from_fn(|i, _| d[i] * unit(i, length)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::so3;
    use glam::DVec3;

    #[test]
    fn apply_moves_each_group() {
        let p = Pose::IDENTITY;
        let q = apply(&p, &[0.0, 0.0, 0.1, 1.0, 0.0, 0.0, 0.0, (2f64).ln(), 0.0], 0.5);
        assert!((so3::geodesic_deg(p.rotation, q.rotation) - 0.1f64.to_degrees()).abs() < 1e-9);
        assert!((q.translation - DVec3::new(0.5, 0.0, 0.0)).length() < 1e-12);
        assert!((q.scale - DVec3::new(1.0, 2.0, 1.0)).length() < 1e-12);
        let g = scale_gradient(&[1.0; 9], 0.5);
        assert_eq!(g[3], 0.5);
        assert_eq!(g[0], 1.0);
    }

    #[test]
    fn each_scale_mode_frees_its_parameters() {
        for (mode, k) in [
            (ScaleMode::Anisotropic, 9),
            (ScaleMode::Isotropic, 7),
            (ScaleMode::Fixed, 6),
        ] {
            let p = mode.basis();
            assert_eq!((p.nrows(), p.ncols()), (9, k));
            // A vector restricted to the mode lies in the basis's span.
            let mut d = [0.3, -0.1, 0.2, 1.0, 2.0, 3.0, 0.5, -0.25, 0.1];
            mode.restrict(&mut d);
            let v = nalgebra::DVector::from_column_slice(&d);
            let proj = &p * (p.transpose() * &p).try_inverse().unwrap() * p.transpose() * &v;
            assert!((proj - &v).norm() < 1e-12, "{mode:?}");
        }
        let mut d = [1.0; 9];
        d[6] = 4.0;
        ScaleMode::Isotropic.restrict(&mut d);
        assert_eq!(&d[6..], &[2.0; 3]);
        ScaleMode::Fixed.restrict(&mut d);
        assert_eq!(&d[6..], &[0.0; 3]);
        assert!(!ScaleMode::Fixed.fits_scale() && ScaleMode::Isotropic.fits_scale());
    }
}
