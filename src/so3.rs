//! Rotations: the exponential and logarithm maps of SO(3), geodesic distance,
//! Euler angles (intrinsic XYZ, degrees, display only) and rotation sampling.
//!
//! All rotations are `glam::DMat3` (column-major storage, acting on column vectors).
//! Tangent vectors ω are axis × angle in radians.

use glam::{DMat3, DQuat, DVec3};

/// The skew-symmetric matrix `[v]×` with `[v]× u = v × u`.
pub fn hat(v: DVec3) -> DMat3 {
    DMat3::from_cols(
        DVec3::new(0.0, v.z, -v.y),
        DVec3::new(-v.z, 0.0, v.x),
        DVec3::new(v.y, -v.x, 0.0),
    )
}

/// `exp([ω]×)`: the rotation by |ω| radians about ω/|ω| (Rodrigues).
pub fn exp(w: DVec3) -> DMat3 {
    let theta2 = w.length_squared();
    let k = hat(w);
    let (a, b) = if theta2 < 1e-12 {
        (1.0 - theta2 / 6.0, 0.5 - theta2 / 24.0)
    } else {
        let t = theta2.sqrt();
        (t.sin() / t, (1.0 - t.cos()) / theta2)
    };
    DMat3::IDENTITY + k * a + (k * k) * b
}

/// The inverse of [`exp`]: the tangent vector ω (|ω| ≤ π) of a rotation.
pub fn log(r: DMat3) -> DVec3 {
    let q = DQuat::from_mat3(&r).normalize();
    let q = if q.w < 0.0 { -q } else { q };
    let v = DVec3::new(q.x, q.y, q.z);
    let s = v.length();
    if s < 1e-12 {
        return v * 2.0;
    }
    let angle = 2.0 * s.atan2(q.w);
    v * (angle / s)
}

/// Geodesic angle between two rotations, in degrees (0..=180).
pub fn geodesic_deg(a: DMat3, b: DMat3) -> f64 {
    let r = a.transpose() * b;
    let c = ((r.x_axis.x + r.y_axis.y + r.z_axis.z - 1.0) * 0.5).clamp(-1.0, 1.0);
    c.acos().to_degrees()
}

/// Rotation from intrinsic XYZ Euler angles in degrees: `R = Rx(a) · Ry(b) · Rz(c)`.
pub fn from_euler_xyz_deg(e: DVec3) -> DMat3 {
    DMat3::from_rotation_x(e.x.to_radians())
        * DMat3::from_rotation_y(e.y.to_radians())
        * DMat3::from_rotation_z(e.z.to_radians())
}

/// Intrinsic XYZ Euler angles in degrees of a rotation (inverse of [`from_euler_xyz_deg`]).
pub fn to_euler_xyz_deg(r: DMat3) -> DVec3 {
    // R = Rx Ry Rz; row 0 col 2 = sin(b).
    let r02 = r.z_axis.x;
    let b = r02.clamp(-1.0, 1.0).asin();
    let (a, c) = if r02.abs() < 0.999_999 {
        let a = (-r.z_axis.y).atan2(r.z_axis.z);
        let c = (-r.y_axis.x).atan2(r.x_axis.x);
        (a, c)
    } else {
        // Gimbal lock: put everything in a.
        (r.y_axis.z.atan2(r.y_axis.y), 0.0)
    };
    DVec3::new(a.to_degrees(), b.to_degrees(), c.to_degrees())
}

/// Projects a nearly orthonormal matrix onto SO(3) (through its quaternion).
pub fn orthonormalize(r: DMat3) -> DMat3 {
    DMat3::from_quat(DQuat::from_mat3(&r).normalize())
}

/// How far from SO(3) a rotation on the wire may be (max |RᵀR − I|, |det − 1|) and
/// still be accepted, projected onto the nearest rotation with a warning (SPEC §2):
/// real calibration data and forward kinematics printed with finite digits are never
/// exactly orthonormal.
pub const SO3_TOLERANCE: f64 = 0.05;

/// Deviations below this are rounding, accepted without a warning.
pub const SO3_SILENT: f64 = 1e-6;

/// The rotation nearest to `r` in the Frobenius norm (the orthogonal factor of its
/// polar decomposition), by Newton's iteration `X ← ½(X + X⁻ᵀ)`, which converges
/// quadratically from any non-singular `r`; `r` must have a positive determinant.
pub fn nearest_rotation(r: DMat3) -> DMat3 {
    let mut x = r;
    for _ in 0..30 {
        let next = (x + x.inverse().transpose()) * 0.5;
        let change = (next - x).to_cols_array().iter().fold(0.0f64, |m, v| m.max(v.abs()));
        x = next;
        if change < 1e-15 {
            break;
        }
    }
    // One last clean-up of rounding.
    orthonormalize(x)
}

/// Accepts a rotation from the wire: returns it projected onto SO(3) and its
/// deviation ([`orthonormality_error`]) when that is within [`SO3_TOLERANCE`] and the
/// determinant is positive; otherwise a message saying why it is not a rotation.
pub fn accept_rotation(r: DMat3) -> std::result::Result<(DMat3, f64), String> {
    if !r.is_finite() {
        return Err("contains a non-finite number".into());
    }
    let e = orthonormality_error(r);
    let det = r.determinant();
    if det.abs() < 1e-6 {
        return Err(format!("is singular (det = {det:.2e})"));
    }
    if det < 0.0 {
        return Err(format!("is a reflection, not a rotation (det = {det:.3})"));
    }
    if e > SO3_TOLERANCE {
        return Err(format!(
            "is not orthonormal (|RᵀR − I|, |det − 1| up to {e:.2e}; at most {SO3_TOLERANCE} is accepted)"
        ));
    }
    Ok((if e > 0.0 { nearest_rotation(r) } else { r }, e))
}

/// Largest absolute entry of `RᵀR − I`, and the determinant: how far `r` is from a rotation.
pub fn orthonormality_error(r: DMat3) -> f64 {
    let e = r.transpose() * r - DMat3::IDENTITY;
    let m = e.to_cols_array().iter().fold(0.0f64, |m, x| m.max(x.abs()));
    m.max((r.determinant() - 1.0).abs())
}

/// `n` rotations spread uniformly over SO(3): a deterministic super-Fibonacci
/// spiral (Alexa, CVPR 2022), so that the same `n` always gives the same set.
pub fn uniform_samples(n: usize) -> Vec<DMat3> {
    let phi = std::f64::consts::SQRT_2;
    let psi = 1.533_751_168_755_204_3; // root of x^4 = x + 4
    (0..n)
        .map(|i| {
            let s = i as f64 + 0.5;
            let r = (s / n as f64).sqrt();
            let big_r = (1.0 - s / n as f64).sqrt();
            let alpha = 2.0 * std::f64::consts::PI * s / phi;
            let beta = 2.0 * std::f64::consts::PI * s / psi;
            let q =
                DQuat::from_xyzw(r * alpha.sin(), r * alpha.cos(), big_r * beta.sin(), big_r * beta.cos()).normalize();
            DMat3::from_quat(q)
        })
        .collect()
}

/// The paper's grid: `k` bins per intrinsic-XYZ Euler axis, each at its bin centre
/// (x and z over 360°, y over 180°), `k³` rotations.
pub fn euler_grid(k: usize) -> Vec<DMat3> {
    let mut out = Vec::with_capacity(k * k * k);
    for i in 0..k {
        for j in 0..k {
            for l in 0..k {
                let a = -180.0 + 360.0 * (i as f64 + 0.5) / k as f64;
                let b = -90.0 + 180.0 * (j as f64 + 0.5) / k as f64;
                let c = -180.0 + 360.0 * (l as f64 + 0.5) / k as f64;
                out.push(from_euler_xyz_deg(DVec3::new(a, b, c)));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn near_rotations_are_projected_and_far_ones_refused() {
        let r = exp(DVec3::new(0.3, -0.2, 0.5));
        // Rows perturbed by 1e-2, as rounded annotations are.
        let noisy = r + DMat3::from_cols_array(&[0.004, -0.006, 0.002, 0.0, 0.005, -0.003, 0.001, 0.0, -0.004]);
        let (got, e) = accept_rotation(noisy).unwrap();
        assert!(e > 1e-3 && e < SO3_TOLERANCE, "{e}");
        assert!(orthonormality_error(got) < 1e-12);
        // The nearest rotation is at least as close to the input as the true one.
        let dist = |a: DMat3, b: DMat3| (a - b).to_cols_array().iter().map(|v| v * v).sum::<f64>();
        assert!(dist(got, noisy) <= dist(r, noisy) + 1e-15);
        assert!(geodesic_deg(got, r) < 1.0);
        assert!(accept_rotation(r * 2.0).unwrap_err().contains("not orthonormal"));
        assert!(accept_rotation(DMat3::ZERO).unwrap_err().contains("singular"));
        let reflect = DMat3::from_diagonal(DVec3::new(1.0, 1.0, -1.0));
        assert!(accept_rotation(reflect).unwrap_err().contains("reflection"));
        assert!(geodesic_deg(accept_rotation(r).unwrap().0, r) < 1e-9);
    }

    #[test]
    fn exp_log_round_trip() {
        for w in [
            DVec3::new(0.1, -0.2, 0.3),
            DVec3::new(3.0, 0.1, -0.2) * 0.9,
            DVec3::new(1e-9, 0.0, 0.0),
        ] {
            let r = exp(w);
            assert!(orthonormality_error(r) < 1e-12);
            assert!((log(r) - w).length() < 1e-9, "{w:?} -> {:?}", log(r));
        }
    }

    #[test]
    fn exp_matches_glam_axis_angle() {
        let w = DVec3::new(0.3, -0.5, 0.8);
        let g = DMat3::from_axis_angle(w.normalize(), w.length());
        assert!((exp(w) - g).abs_diff_eq(DMat3::ZERO, 1e-12));
    }

    #[test]
    fn euler_round_trip_and_geodesic() {
        let e = DVec3::new(30.0, -40.0, 100.0);
        let r = from_euler_xyz_deg(e);
        assert!((to_euler_xyz_deg(r) - e).length() < 1e-9);
        let r2 = r * exp(DVec3::new(0.0, 0.0, 10f64.to_radians()));
        assert!((geodesic_deg(r, r2) - 10.0).abs() < 1e-9);
    }

    #[test]
    fn uniform_samples_cover_so3() {
        let s = uniform_samples(512);
        // Every random rotation has a sample within 30 degrees.
        for k in 0..50 {
            let w = DVec3::new((k as f64 * 1.7).sin(), (k as f64 * 2.3).cos(), (k as f64 * 0.7).sin()) * 2.5;
            let r = exp(w);
            let best = s.iter().map(|q| geodesic_deg(*q, r)).fold(f64::MAX, f64::min);
            assert!(best < 30.0, "gap {best}");
        }
        assert_eq!(euler_grid(4).len(), 64);
    }
}
