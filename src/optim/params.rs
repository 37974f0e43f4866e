//! The optimiser's parameters: a 9-vector of increments applied to the current pose,
//! `R ← R·exp([ω]×)`, `t ← t + L·τ`, `s ← s ⊙ exp(ℓ)`, where L is the object's
//! radius in the world (so one step size serves any object size, unit and camera
//! distance). Order: [ω0, ω1, ω2, τ0, τ1, τ2, ℓ0, ℓ1, ℓ2].

use crate::pose::Pose;
use crate::so3;
use glam::DVec3;

/// Converts a gradient in pose units [ω, t, log s] into the scaled parameters [ω, τ, ℓ].
pub fn scale_gradient(g: &[f64; 9], length: f64) -> [f64; 9] {
    let mut out = *g;
    for v in &mut out[3..6] {
        *v *= length;
    }
    out
}

/// Applies a scaled increment to a pose.
pub fn apply(pose: &Pose, d: &[f64; 9], length: f64) -> Pose {
    Pose {
        rotation: so3::orthonormalize(pose.rotation * so3::exp(DVec3::new(d[0], d[1], d[2]))),
        translation: pose.translation + DVec3::new(d[3], d[4], d[5]) * length,
        scale: pose.scale * DVec3::new(d[6], d[7], d[8]).exp(),
    }
}

/// Keeps only the isotropic part of a log-scale increment (for fits with a uniform scale).
pub fn isotropic_scale(d: &mut [f64; 9]) {
    let m = (d[6] + d[7] + d[8]) / 3.0;
    d[6] = m;
    d[7] = m;
    d[8] = m;
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
