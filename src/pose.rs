//! The object's 9-DoF pose Φ = [sR | t]: a model point X_o maps to the world as
//! `X_w = R · (s ⊙ X_o) + t` (SPEC §2), and its wire form (rotation as a 3×3
//! row-major matrix or a unit quaternion [w, x, y, z]).

use crate::error::{Error, Result};
use crate::so3;
use glam::{DMat3, DMat4, DQuat, DVec3};
use nalgebra::{SMatrix, SVector};
use serde::{Deserialize, Serialize};

/// The pose's tangent dimension: `[ω (3), t (3), log s (3)]`.
pub const POSE_DIM: usize = 9;
/// A 9×9 matrix in pose coordinates `[ω, t, log s]` (curvatures, covariances): the one
/// 9×9 type of the crate.
pub type Mat9 = SMatrix<f64, POSE_DIM, POSE_DIM>;
/// A 9-vector in pose coordinates `[ω, t, log s]`.
pub type Vec9 = SVector<f64, POSE_DIM>;

/// Rotation, translation and per-axis scale of the object in the world.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    /// Object-to-world rotation (orthonormal, det +1).
    pub rotation: DMat3,
    /// Object origin in the world.
    pub translation: DVec3,
    /// Per-axis scale, applied in the model frame before rotating (all > 0).
    pub scale: DVec3,
}

impl Default for Pose {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Pose {
    /// Identity rotation, zero translation, unit scale.
    pub const IDENTITY: Pose = Pose {
        rotation: DMat3::IDENTITY,
        translation: DVec3::ZERO,
        scale: DVec3::ONE,
    };

    /// Maps a model point into the world.
    #[inline]
    pub fn apply(&self, p: DVec3) -> DVec3 {
        self.rotation * (self.scale * p) + self.translation
    }

    /// The pose moved by `d` in `[ω, t, log s]`: `R·exp([ω]×)`, `t + δt`, `s ⊙ exp(δlog s)`
    /// (ω the right tangent, as every gradient and covariance of the crate).
    pub fn perturbed(&self, d: &Vec9) -> Pose {
        Pose {
            rotation: so3::orthonormalize(self.rotation * so3::exp(DVec3::new(d[0], d[1], d[2]))),
            translation: self.translation + DVec3::new(d[3], d[4], d[5]),
            scale: self.scale * DVec3::new(d[6], d[7], d[8]).exp(),
        }
    }

    /// The 4×4 object-to-world matrix `[R·diag(s) | t]`.
    pub fn matrix(&self) -> DMat4 {
        let m = self.rotation * DMat3::from_diagonal(self.scale);
        DMat4::from_cols(
            m.x_axis.extend(0.0),
            m.y_axis.extend(0.0),
            m.z_axis.extend(0.0),
            self.translation.extend(1.0),
        )
    }

    /// The rotation as a unit quaternion with w ≥ 0.
    pub fn quaternion(&self) -> DQuat {
        let q = DQuat::from_mat3(&self.rotation).normalize();
        if q.w < 0.0 {
            -q
        } else {
            q
        }
    }

    /// Checks that every number is finite, the scale positive and the rotation orthonormal.
    pub fn validate(&self) -> Result<()> {
        let finite = self.rotation.is_finite() && self.translation.is_finite() && self.scale.is_finite();
        if !finite {
            return Err(Error::Pose("contains a non-finite number".into()));
        }
        if self.scale.min_element() <= 0.0 {
            return Err(Error::Pose(format!(
                "scale must be positive, got {:?}",
                self.scale.to_array()
            )));
        }
        let (lo, hi) = crate::limits::SCALE_RANGE;
        if self.scale.min_element() < lo || self.scale.max_element() > hi {
            return Err(Error::Pose(format!(
                "scale {:?} is outside the factors accepted ({lo:e} to {hi:e})",
                self.scale.to_array()
            )));
        }
        if let Some(p) = self
            .translation
            .to_array()
            .into_iter()
            .find_map(crate::limits::length_problem)
        {
            return Err(Error::Pose(format!(
                "translation {:?}: {p}",
                self.translation.to_array()
            )));
        }
        let e = so3::orthonormality_error(self.rotation);
        if e > 1e-3 {
            return Err(Error::Pose(format!("rotation is not orthonormal (error {e:.2e})")));
        }
        Ok(())
    }

    /// Parses the wire form (see [`PoseJson`]); `file` names the source in errors.
    pub fn from_json_str(text: &str, file: &str) -> Result<Pose> {
        crate::limits::check_json_depth(file, text.as_bytes())?;
        let pj: PoseJson = serde_json::from_str(text).map_err(|e| Error::Json {
            file: file.into(),
            problem: e.to_string(),
        })?;
        pj.to_pose().map_err(|e| Error::Json {
            file: file.into(),
            problem: e.to_string(),
        })
    }
}

/// A rotation on the wire: a 3×3 row-major matrix or a quaternion [w, x, y, z].
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(untagged)]
pub enum RotationJson {
    /// 3×3 row-major matrix.
    Matrix([[f64; 3]; 3]),
    /// Unit quaternion [w, x, y, z].
    Quaternion([f64; 4]),
}

/// The pose's wire form, as in `scene.json` and result files.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct PoseJson {
    /// Rotation: a 3×3 matrix (row-major) or a quaternion [w, x, y, z].
    pub rotation: Option<RotationJson>,
    /// Alternatively, the quaternion [w, x, y, z] under its own key.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub quaternion: Option<[f64; 4]>,
    /// Translation.
    pub translation: [f64; 3],
    /// Per-axis scale (default [1, 1, 1]).
    #[serde(default = "one3")]
    pub scale: [f64; 3],
}

fn one3() -> [f64; 3] {
    [1.0; 3]
}

/// Row-major 3×3 array from a glam matrix.
pub fn mat3_to_rows(m: DMat3) -> [[f64; 3]; 3] {
    let t = m.transpose();
    [t.x_axis.to_array(), t.y_axis.to_array(), t.z_axis.to_array()]
}

/// glam matrix from a row-major 3×3 array.
pub fn mat3_from_rows(r: [[f64; 3]; 3]) -> DMat3 {
    DMat3::from_cols_array_2d(&r).transpose()
}

/// Row-major 4×4 array from a glam matrix.
pub fn mat4_to_rows(m: DMat4) -> [[f64; 4]; 4] {
    let t = m.transpose();
    [
        t.x_axis.to_array(),
        t.y_axis.to_array(),
        t.z_axis.to_array(),
        t.w_axis.to_array(),
    ]
}

/// glam matrix from a row-major 4×4 array.
pub fn mat4_from_rows(r: [[f64; 4]; 4]) -> DMat4 {
    DMat4::from_cols_array_2d(&r).transpose()
}

impl PoseJson {
    /// The wire form of a pose (rotation as a matrix).
    pub fn from_pose(p: &Pose) -> Self {
        PoseJson {
            rotation: Some(RotationJson::Matrix(mat3_to_rows(p.rotation))),
            quaternion: None,
            translation: p.translation.to_array(),
            scale: p.scale.to_array(),
        }
    }

    /// Converts and validates (a rotation slightly off SO(3) is projected onto it;
    /// see [`PoseJson::to_pose_with_warning`]).
    pub fn to_pose(&self) -> Result<Pose> {
        self.to_pose_with_warning().map(|(p, _)| p)
    }

    /// Converts and validates; also returns the rotation's deviation from SO(3)
    /// (max |RᵀR − I|, |det − 1|) when it was more than rounding and the rotation was
    /// projected onto the nearest one (at most [`so3::SO3_TOLERANCE`] is accepted).
    pub fn to_pose_with_warning(&self) -> Result<(Pose, Option<f64>)> {
        let (rot, deviation) = match (&self.rotation, &self.quaternion) {
            (Some(RotationJson::Matrix(m)), _) => {
                so3::accept_rotation(mat3_from_rows(*m)).map_err(|why| Error::Pose(format!("rotation {why}")))?
            }
            (Some(RotationJson::Quaternion(q)), _) | (None, Some(q)) => quat_wxyz(*q)?,
            (None, None) => (DMat3::IDENTITY, 0.0),
        };
        let pose = Pose {
            rotation: rot,
            translation: DVec3::from_array(self.translation),
            scale: DVec3::from_array(self.scale),
        };
        pose.validate()?;
        Ok((pose, (deviation > so3::SO3_SILENT).then_some(deviation)))
    }
}

fn quat_wxyz(q: [f64; 4]) -> Result<(DMat3, f64)> {
    let q = DQuat::from_xyzw(q[1], q[2], q[3], q[0]);
    if !q.is_finite() {
        return Err(Error::Pose("quaternion contains a non-finite number".into()));
    }
    let n = q.length();
    if (n - 1.0).abs() > so3::SO3_TOLERANCE {
        return Err(Error::Pose(format!("quaternion is not unit length (|q| = {n:.4})")));
    }
    Ok((DMat3::from_quat(q / n), (n - 1.0).abs()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matrix_and_apply_agree() {
        let p = Pose {
            rotation: so3::exp(DVec3::new(0.2, -0.4, 0.9)),
            translation: DVec3::new(1.0, 2.0, -3.0),
            scale: DVec3::new(1.0, 0.5, 2.0),
        };
        let x = DVec3::new(0.3, -0.7, 1.1);
        assert!((p.matrix().transform_point3(x) - p.apply(x)).length() < 1e-12);
    }

    #[test]
    fn json_round_trip_matrix_and_quaternion() {
        let p = Pose {
            rotation: so3::exp(DVec3::new(0.2, -0.4, 0.9)),
            translation: DVec3::new(1.0, 2.0, -3.0),
            scale: DVec3::new(1.0, 0.5, 2.0),
        };
        let s = serde_json::to_string(&PoseJson::from_pose(&p)).unwrap();
        let back = Pose::from_json_str(&s, "p.json").unwrap();
        assert!((back.rotation - p.rotation).abs_diff_eq(DMat3::ZERO, 1e-12));
        let q = p.quaternion();
        let text = format!(
            r#"{{"rotation":[{},{},{},{}],"translation":[1,2,-3],"scale":[1,0.5,2]}}"#,
            q.w, q.x, q.y, q.z
        );
        let back = Pose::from_json_str(&text, "q.json").unwrap();
        assert!(so3::geodesic_deg(back.rotation, p.rotation) < 1e-6);
    }

    #[test]
    fn bad_poses_are_rejected() {
        let e = Pose::from_json_str(
            r#"{"rotation":[[1,0,0],[0,1,0],[0,0,1]],"translation":[0,0,0],"scale":[0,1,1]}"#,
            "a.json",
        );
        assert!(e.unwrap_err().to_string().contains("scale must be positive"));
        let e = Pose::from_json_str(
            r#"{"rotation":[[2,0,0],[0,1,0],[0,0,1]],"translation":[0,0,0]}"#,
            "b.json",
        );
        assert!(e.unwrap_err().to_string().contains("not orthonormal"));
        let e = Pose::from_json_str(r#"{"rotation":[1,0,0,0],"translation":[0,NaN,0]}"#, "c.json");
        assert!(e.unwrap_err().to_string().starts_with("c.json"));
        // Rounded annotations are projected, with the deviation reported.
        let pj: PoseJson =
            serde_json::from_str(r#"{"rotation":[[1,0.008,0],[0,1,0],[0,0,1]],"translation":[0,0,0]}"#).unwrap();
        let (p, dev) = pj.to_pose_with_warning().unwrap();
        assert!((dev.unwrap() - 0.008).abs() < 1e-3);
        assert!(so3::orthonormality_error(p.rotation) < 1e-12);
        let e = Pose::from_json_str(r#"{"rotation":[0,0,0,0],"translation":[0,0,0]}"#, "c.json");
        assert!(e.unwrap_err().to_string().starts_with("c.json"));
    }
}
