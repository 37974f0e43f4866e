//! Pinhole cameras in the OpenCV convention (SPEC §2): camera x right, y down,
//! z forward; a camera point (x, y, z), z > 0, projects to
//! `u = fx·x/z + cx`, `v = fy·y/z + cy`, the centre of the top-left pixel being (0, 0).
//!
//! Cameras arrive as [`CameraJson`] (`world_to_camera` or `camera_to_world`, 4×4
//! row-major, OpenCV or OpenGL axes) and are validated and normalised to OpenCV here.

use crate::error::{Error, Result};
use crate::pose::{mat3_to_rows, mat4_from_rows, mat4_to_rows};
use crate::so3;
use glam::{DMat3, DMat4, DVec2, DVec3};
use serde::{Deserialize, Serialize};

/// Largest accepted image side, in pixels.
pub const MAX_SIDE: u32 = 16384;

/// A validated pinhole camera, OpenCV axes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Focal length along x, pixels.
    pub fx: f64,
    /// Focal length along y, pixels.
    pub fy: f64,
    /// Principal point x, pixels (pixel centres at integers).
    pub cx: f64,
    /// Principal point y, pixels.
    pub cy: f64,
    /// World-to-camera rotation R_wc.
    pub rotation: DMat3,
    /// World-to-camera translation t_wc.
    pub translation: DVec3,
}

/// Axis convention of a camera on the wire.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Convention {
    /// x right, y down, z forward.
    #[default]
    Opencv,
    /// x right, y up, z backward (Blender, NeRF, glTF).
    Opengl,
}

/// A camera as written in `scene.json` (SPEC §3).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct CameraJson {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Focal length x, pixels.
    pub fx: f64,
    /// Focal length y, pixels.
    pub fy: f64,
    /// Principal point x, pixels.
    pub cx: f64,
    /// Principal point y, pixels.
    pub cy: f64,
    /// World-to-camera 4×4, row-major.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub world_to_camera: Option<[[f64; 4]; 4]>,
    /// Camera-to-world 4×4, row-major (alternative to `world_to_camera`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub camera_to_world: Option<[[f64; 4]; 4]>,
    /// `"opencv"` (default) or `"opengl"`.
    #[serde(default)]
    pub convention: Convention,
}

fn cam_err(view: &str, problem: impl Into<String>) -> Error {
    Error::Camera {
        view: view.into(),
        problem: problem.into(),
    }
}

impl CameraJson {
    /// Validates and converts to an OpenCV [`Camera`]; `view` names the view in errors.
    /// A rotation slightly off SO(3) is projected (see [`CameraJson::to_camera_with_warning`]).
    pub fn to_camera(&self, view: &str) -> Result<Camera> {
        self.to_camera_with_warning(view).map(|(c, _)| c)
    }

    /// As [`CameraJson::to_camera`], with the warning to show when the extrinsics'
    /// rotation was off SO(3) by more than rounding (up to [`so3::SO3_TOLERANCE`]) and
    /// was projected onto the nearest rotation.
    pub fn to_camera_with_warning(&self, view: &str) -> Result<(Camera, Option<String>)> {
        for (name, v) in [("fx", self.fx), ("fy", self.fy), ("cx", self.cx), ("cy", self.cy)] {
            if !v.is_finite() {
                return Err(cam_err(view, format!("{name} is not a finite number")));
            }
        }
        if self.fx <= 0.0 || self.fy <= 0.0 {
            return Err(cam_err(
                view,
                format!("focal lengths must be positive (fx = {}, fy = {})", self.fx, self.fy),
            ));
        }
        let (lo, hi) = crate::limits::FOCAL_RANGE_PX;
        for (name, v) in [("fx", self.fx), ("fy", self.fy)] {
            if !(lo..=hi).contains(&v) {
                return Err(cam_err(
                    view,
                    format!("{name} = {v:e} pixels is outside the focal lengths accepted ({lo:e} to {hi:e})"),
                ));
            }
        }
        let c = crate::limits::MAX_PRINCIPAL_PX;
        for (name, v) in [("cx", self.cx), ("cy", self.cy)] {
            if v.abs() > c {
                return Err(cam_err(
                    view,
                    format!("{name} = {v:e} pixels is beyond ±{c:e}: the principal point must be near the image"),
                ));
            }
        }
        if self.width == 0 || self.height == 0 || self.width > MAX_SIDE || self.height > MAX_SIDE {
            return Err(cam_err(
                view,
                format!(
                    "width and height must be between 1 and {MAX_SIDE} (got {}×{})",
                    self.width, self.height
                ),
            ));
        }
        let (key, rows) = match (self.world_to_camera, self.camera_to_world) {
            (Some(_), Some(_)) => {
                return Err(cam_err(
                    view,
                    "give either world_to_camera or camera_to_world, not both",
                ))
            }
            (None, None) => return Err(cam_err(view, "needs world_to_camera or camera_to_world")),
            (Some(m), None) => ("world_to_camera", m),
            (None, Some(m)) => ("camera_to_world", m),
        };
        let (m, deviation) = check_rigid(view, key, rows)?;
        let w2c = if key == "world_to_camera" { m } else { rigid_inverse(m) };
        let w2c = match self.convention {
            Convention::Opencv => w2c,
            Convention::Opengl => DMat4::from_diagonal(glam::DVec4::new(1.0, -1.0, -1.0, 1.0)) * w2c,
        };
        let warning = (deviation > so3::SO3_SILENT).then(|| {
            format!(
                "view '{view}': camera: {key}'s rotation is off SO(3) by {deviation:.2e} \
                 (max |RᵀR − I|, |det − 1|): projected onto the nearest rotation"
            )
        });
        let camera = Camera {
            width: self.width,
            height: self.height,
            fx: self.fx,
            fy: self.fy,
            cx: self.cx,
            cy: self.cy,
            rotation: DMat3::from_mat4(w2c),
            translation: w2c.w_axis.truncate(),
        };
        Ok((camera, warning))
    }

    /// The wire form of a camera (world_to_camera, OpenCV).
    pub fn from_camera(c: &Camera) -> Self {
        CameraJson {
            width: c.width,
            height: c.height,
            fx: c.fx,
            fy: c.fy,
            cx: c.cx,
            cy: c.cy,
            world_to_camera: Some(mat4_to_rows(c.world_to_camera_matrix())),
            camera_to_world: None,
            convention: Convention::Opencv,
        }
    }
}

/// The inverse of a rigid transform whose rotation is exactly orthonormal.
fn rigid_inverse(m: DMat4) -> DMat4 {
    let r = DMat3::from_mat4(m).transpose();
    let t = -(r * m.w_axis.truncate());
    DMat4::from_cols(
        r.x_axis.extend(0.0),
        r.y_axis.extend(0.0),
        r.z_axis.extend(0.0),
        t.extend(1.0),
    )
}

/// Checks a 4×4 rigid transform from the wire; returns it with its rotation
/// projected onto SO(3), and the rotation's deviation from SO(3).
fn check_rigid(view: &str, key: &str, rows: [[f64; 4]; 4]) -> Result<(DMat4, f64)> {
    if rows.iter().flatten().any(|v| !v.is_finite()) {
        return Err(cam_err(view, format!("{key} contains a non-finite number")));
    }
    for (i, row) in rows.iter().take(3).enumerate() {
        if let Some(p) = crate::limits::length_problem(row[3]) {
            return Err(cam_err(view, format!("{key}'s translation (row {i}, column 3) {p}")));
        }
    }
    let last = rows[3];
    if last[0].abs() > 1e-6 || last[1].abs() > 1e-6 || last[2].abs() > 1e-6 || (last[3] - 1.0).abs() > 1e-6 {
        return Err(cam_err(
            view,
            format!("{key}'s last row must be [0, 0, 0, 1], got {last:?}"),
        ));
    }
    let m = mat4_from_rows(rows);
    let r = DMat3::from_mat4(m);
    let (rot, e) = so3::accept_rotation(r).map_err(|why| {
        cam_err(
            view,
            format!("{key}'s rotation part {why} (rows {:?})", mat3_to_rows(r)),
        )
    })?;
    let out = DMat4::from_cols(
        rot.x_axis.extend(0.0),
        rot.y_axis.extend(0.0),
        rot.z_axis.extend(0.0),
        m.w_axis.truncate().extend(1.0),
    );
    Ok((out, e))
}

impl Camera {
    /// World point to camera frame.
    #[inline]
    pub fn to_camera(&self, p: DVec3) -> DVec3 {
        self.rotation * p + self.translation
    }

    /// Camera-frame point (z > 0) to pixel coordinates.
    #[inline]
    pub fn project(&self, pc: DVec3) -> DVec2 {
        DVec2::new(self.fx * pc.x / pc.z + self.cx, self.fy * pc.y / pc.z + self.cy)
    }

    /// Pixel coordinates and the 2×3 Jacobian `∂(u, v)/∂(x, y, z)` (rows u, v).
    #[inline]
    pub fn project_with_jacobian(&self, pc: DVec3) -> (DVec2, [DVec3; 2]) {
        let iz = 1.0 / pc.z;
        let x = pc.x * iz;
        let y = pc.y * iz;
        let uv = DVec2::new(self.fx * x + self.cx, self.fy * y + self.cy);
        let ju = DVec3::new(self.fx * iz, 0.0, -self.fx * x * iz);
        let jv = DVec3::new(0.0, self.fy * iz, -self.fy * y * iz);
        (uv, [ju, jv])
    }

    /// The camera's centre in the world.
    pub fn centre(&self) -> DVec3 {
        -(self.rotation.transpose() * self.translation)
    }

    /// The world direction (unit) of the ray through pixel (u, v).
    pub fn ray_direction(&self, u: f64, v: f64) -> DVec3 {
        let d = DVec3::new((u - self.cx) / self.fx, (v - self.cy) / self.fy, 1.0);
        (self.rotation.transpose() * d).normalize()
    }

    /// The 4×4 world-to-camera matrix.
    pub fn world_to_camera_matrix(&self) -> DMat4 {
        DMat4::from_cols(
            self.rotation.x_axis.extend(0.0),
            self.rotation.y_axis.extend(0.0),
            self.rotation.z_axis.extend(0.0),
            self.translation.extend(1.0),
        )
    }

    /// A copy for an image resized by `factor` (e.g. 0.5 halves each side): focal
    /// lengths scale, and the principal point follows the pixel-centre convention.
    pub fn scaled(&self, width: u32, height: u32) -> Camera {
        let sx = width as f64 / self.width as f64;
        let sy = height as f64 / self.height as f64;
        Camera {
            width,
            height,
            fx: self.fx * sx,
            fy: self.fy * sy,
            cx: (self.cx + 0.5) * sx - 0.5,
            cy: (self.cy + 0.5) * sy - 0.5,
            ..*self
        }
    }

    /// A camera at `eye` looking at `target`, with image-up roughly along world `up`.
    pub fn look_at(eye: DVec3, target: DVec3, up: DVec3, width: u32, height: u32, f: f64) -> Camera {
        let z = (target - eye).normalize();
        let mut x = z.cross(up);
        if x.length_squared() < 1e-12 {
            x = z.any_orthonormal_vector();
        }
        let x = x.normalize();
        let y = z.cross(x);
        // Rows of R_wc are the camera axes in world coordinates.
        let r = DMat3::from_cols(x, y, z).transpose();
        Camera {
            width,
            height,
            fx: f,
            fy: f,
            cx: (width as f64 - 1.0) * 0.5,
            cy: (height as f64 - 1.0) * 0.5,
            rotation: r,
            translation: -(r * eye),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn json(w2c: [[f64; 4]; 4]) -> CameraJson {
        CameraJson {
            width: 640,
            height: 480,
            fx: 600.0,
            fy: 600.0,
            cx: 319.5,
            cy: 239.5,
            world_to_camera: Some(w2c),
            camera_to_world: None,
            convention: Convention::Opencv,
        }
    }
    const ID_Z2: [[f64; 4]; 4] = [[1., 0., 0., 0.], [0., 1., 0., 0.], [0., 0., 1., 2.], [0., 0., 0., 1.]];

    #[test]
    fn spec_example_projects_origin_to_centre() {
        let c = json(ID_Z2).to_camera("left").unwrap();
        let uv = c.project(c.to_camera(DVec3::ZERO));
        assert!((uv - DVec2::new(319.5, 239.5)).length() < 1e-12);
        let uv = c.project(c.to_camera(DVec3::new(0.1, 0.2, 0.0)));
        assert!((uv - DVec2::new(319.5 + 30.0, 239.5 + 60.0)).length() < 1e-9);
        assert!((c.centre() - DVec3::new(0., 0., -2.)).length() < 1e-12);
    }

    #[test]
    fn camera_to_world_and_opengl_agree() {
        let cv = json(ID_Z2).to_camera("a").unwrap();
        let mut j = json(ID_Z2);
        j.world_to_camera = None;
        j.camera_to_world = Some(mat4_to_rows(cv.world_to_camera_matrix().inverse()));
        let c2 = j.to_camera("a").unwrap();
        assert!((c2.translation - cv.translation).length() < 1e-12);
        // The same camera in OpenGL axes: flip y and z of the camera frame.
        let gl = DMat4::from_diagonal(glam::DVec4::new(1.0, -1.0, -1.0, 1.0)) * cv.world_to_camera_matrix();
        let mut j = json(mat4_to_rows(gl));
        j.convention = Convention::Opengl;
        let c3 = j.to_camera("a").unwrap();
        assert!((c3.rotation - cv.rotation).abs_diff_eq(DMat3::ZERO, 1e-12));
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let c = json(ID_Z2).to_camera("a").unwrap();
        let p = DVec3::new(0.3, -0.2, 2.5);
        let (_, j) = c.project_with_jacobian(p);
        let h = 1e-6;
        for k in 0..3 {
            let mut e = DVec3::ZERO;
            e[k] = h;
            let d = (c.project(p + e) - c.project(p - e)) / (2.0 * h);
            assert!((d.x - j[0][k]).abs() < 1e-5 && (d.y - j[1][k]).abs() < 1e-5);
        }
    }

    #[test]
    fn bad_cameras_are_named() {
        let mut j = json(ID_Z2);
        j.fx = f64::NAN;
        assert_eq!(
            j.to_camera("v3").unwrap_err().to_string(),
            "view 'v3': camera: fx is not a finite number"
        );
        let mut j = json(ID_Z2);
        j.fy = -1.0;
        assert!(j
            .to_camera("v")
            .unwrap_err()
            .to_string()
            .contains("focal lengths must be positive"));
        let mut m = ID_Z2;
        m[0][0] = 0.0;
        let e = json(m).to_camera("v").unwrap_err().to_string();
        assert!(e.contains("singular"), "{e}");
        m[0][0] = 1.5;
        assert!(json(m)
            .to_camera("v")
            .unwrap_err()
            .to_string()
            .contains("not orthonormal"));
        let mut j = json(ID_Z2);
        j.world_to_camera = None;
        assert!(j
            .to_camera("v")
            .unwrap_err()
            .to_string()
            .contains("needs world_to_camera"));
    }

    #[test]
    fn near_orthonormal_rotations_load_with_a_warning() {
        let mut m = ID_Z2;
        m[0][1] = 9e-3; // as far off as LM-O's annotations
        let (c, w) = json(m).to_camera_with_warning("cam3").unwrap();
        let w = w.expect("a warning");
        assert!(w.contains("'cam3'") && w.contains("9.00e-3"), "{w}");
        assert!(so3::orthonormality_error(c.rotation) < 1e-12);
        let (_, w) = json(ID_Z2).to_camera_with_warning("cam3").unwrap();
        assert!(w.is_none());
        // Beyond the tolerance, and the bad-input corpus: refused.
        m[0][1] = 0.2;
        assert!(json(m)
            .to_camera("v")
            .unwrap_err()
            .to_string()
            .contains("not orthonormal"));
        let mut doubled = ID_Z2;
        for r in doubled.iter_mut().take(3) {
            for v in r.iter_mut().take(3) {
                *v *= 2.0;
            }
        }
        assert!(json(doubled).to_camera("v").is_err());
    }

    #[test]
    fn look_at_centres_target() {
        let c = Camera::look_at(DVec3::new(1.0, 2.0, 3.0), DVec3::ZERO, DVec3::Y, 101, 81, 100.0);
        let uv = c.project(c.to_camera(DVec3::ZERO));
        assert!((uv - DVec2::new(50.0, 40.0)).length() < 1e-9);
        assert!(c.to_camera(DVec3::ZERO).z > 0.0);
        assert!(so3::orthonormality_error(c.rotation) < 1e-12);
        // World up appears upward (negative v) in the image.
        let up = c.project(c.to_camera(DVec3::Y * 0.1));
        assert!(up.y < 40.0);
    }
}
