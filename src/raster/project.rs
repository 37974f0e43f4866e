//! Projection of a posed mesh into a view: model → world (pose) → camera (OpenCV)
//! → pixels (SPEC §2). The one projection of the crate: the hard, SoftRas and edge
//! rasterisers all take a [`Projected`] mesh, and the soft ones' backward passes use
//! the Jacobians of a [`PoseProjection`] to chain pixel gradients to the 9 pose
//! parameters.
//!
//! Chain rule (pose-gradient order `[ω0, ω1, ω2, t0, t1, t2, ls0, ls1, ls2]`, ω the
//! right tangent `R·exp([ω]×)`, ls the log scale): with `y = s ⊙ X_o`,
//! `X_c = R_wc·(R·y + t) + t_wc` and `h = (R_wc·R)ᵀ·∂L/∂X_c`,
//! `∂L/∂ω = Σ y × h`, `∂L/∂t = R·Σ h`, `∂L/∂ls = Σ y ⊙ h`.

use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::mesh::Mesh;
use crate::pose::Pose;
pub use crate::pose::POSE_DIM;
use glam::{DMat3, DVec2, DVec3};
use wide::f64x2;

/// A mesh's vertices in one camera.
#[derive(Debug, Clone, Default)]
pub struct Projected {
    /// Camera-frame positions (OpenCV axes).
    pub cam: Vec<DVec3>,
    /// Pixel coordinates; NaN where `cam[i].z < near`.
    pub uv: Vec<DVec2>,
    /// The near-plane depth used: points closer than this are "behind" the camera.
    pub near: f64,
}

impl Projected {
    /// Whether vertex `i` is in front of the near plane.
    #[inline]
    pub fn in_front(&self, i: usize) -> bool {
        self.cam[i].z >= self.near
    }
}

/// The near-plane depth for an object of this extent: a tiny fraction of it, so
/// that only points essentially at or behind the camera centre are cut.
pub fn near_plane(mesh_extent: f64) -> f64 {
    (mesh_extent * 1e-4).max(1e-9)
}

/// The near plane for `mesh` under a pose of scale `scale`.
fn near_for(mesh: &Mesh, scale: DVec3) -> f64 {
    let extent = mesh.bounds().map(|b| (b.size() * scale.abs()).length()).unwrap_or(1.0);
    near_plane(extent)
}

/// Projects every vertex of `mesh` under `pose` into `camera`.
pub fn project_mesh(mesh: &Mesh, pose: &Pose, camera: &Camera) -> Projected {
    let mut p = PoseProjection::default();
    p.project(mesh, pose, camera);
    p.proj
}

/// An error naming `view` unless at least one vertex is in front of the camera.
pub fn check_visible(view: &str, proj: &Projected) -> Result<()> {
    if proj.cam.iter().all(|c| c.z < proj.near) {
        return Err(Error::View {
            view: view.into(),
            problem: "the object is entirely behind the camera at this pose".into(),
        });
    }
    Ok(())
}

/// A projection that keeps what the backward passes need: the camera points, the
/// pose and the chain to it (the projection Jacobians are computed per vertex when
/// asked for). Reusable across iterations (buffers kept).
#[derive(Debug, Clone, Default)]
pub struct PoseProjection {
    /// Camera points, pixels, near plane.
    pub proj: Projected,
    pose: Pose,
    camera_rotation: DMat3,
    /// `X_c = m·y + b`, `m = R_wc·R`, `y = s ⊙ X_o` (identity and zero for
    /// [`PoseProjection::from_camera_points`]).
    m: DMat3,
    b: DVec3,
    /// The focal lengths, for the Jacobians (computed per vertex when asked).
    fx: f64,
    fy: f64,
    /// Whether the pose chain is available (not for camera points).
    posed: bool,
}

impl PoseProjection {
    /// Projects `mesh` at `pose` into `camera`. The Jacobians of the backward passes
    /// are computed from the camera points when asked for, only for the vertices asked
    /// for (outline vertices, for the edge rasteriser).
    pub fn project(&mut self, mesh: &Mesh, pose: &Pose, camera: &Camera) {
        let m = camera.rotation * pose.rotation;
        let b = camera.rotation * pose.translation + camera.translation;
        self.proj.cam.clear();
        self.proj
            .cam
            .extend(mesh.positions.iter().map(|p| m * (pose.scale * *p) + b));
        self.pose = *pose;
        self.camera_rotation = camera.rotation;
        (self.m, self.b, self.posed) = (m, b, true);
        self.finish(near_for(mesh, pose.scale), camera);
    }

    /// A projection of given camera-frame points (the camera stage on its own; the
    /// pose chain is then unavailable: [`PoseProjection::camera_gradient`] only).
    pub fn from_camera_points(&mut self, cam: &[DVec3], near: f64, camera: &Camera) {
        self.proj.cam.clear();
        self.proj.cam.extend_from_slice(cam);
        self.pose = Pose::IDENTITY;
        self.camera_rotation = camera.rotation;
        (self.m, self.b, self.posed) = (DMat3::IDENTITY, DVec3::ZERO, false);
        self.finish(near, camera);
    }

    fn finish(&mut self, near: f64, camera: &Camera) {
        self.proj.near = near;
        (self.fx, self.fy) = (camera.fx, camera.fy);
        self.proj.uv.clear();
        self.proj.uv.extend(self.proj.cam.iter().map(|c| {
            if c.z >= near {
                camera.project_with_jacobian(*c).0
            } else {
                DVec2::splat(f64::NAN)
            }
        }));
    }

    /// `∂(u, v)/∂(x, y, z)` of vertex `i` (zero behind the near plane), as
    /// [`Camera::project_with_jacobian`].
    #[inline]
    fn jac(&self, i: usize) -> [DVec3; 2] {
        let c = self.proj.cam[i];
        if c.z < self.proj.near {
            return [DVec3::ZERO; 2];
        }
        let iz = 1.0 / c.z;
        let (x, y) = (c.x * iz, c.y * iz);
        [
            DVec3::new(self.fx * iz, 0.0, -self.fx * x * iz),
            DVec3::new(0.0, self.fy * iz, -self.fy * y * iz),
        ]
    }

    /// `y = s ⊙ X_o` of vertex `i`, recovered from its camera point (callers check
    /// `posed`).
    #[inline]
    fn scaled(&self, i: usize) -> DVec3 {
        self.m.transpose() * (self.proj.cam[i] - self.b)
    }

    /// Pixel positions (NaN behind the near plane).
    pub fn uv(&self) -> &[DVec2] {
        &self.proj.uv
    }

    /// Number of vertices.
    pub fn len(&self) -> usize {
        self.proj.cam.len()
    }

    /// Whether there are no vertices.
    pub fn is_empty(&self) -> bool {
        self.proj.cam.is_empty()
    }

    /// ∂L/∂X_c of vertex `i` from its ∂L/∂(u, v).
    #[inline]
    pub fn camera_gradient(&self, i: usize, g: DVec2) -> DVec3 {
        let j = self.jac(i);
        j[0] * g.x + j[1] * g.y
    }

    /// Chains per-vertex ∂L/∂(u, v) (`grad_uv(i)`) through the projection and the
    /// pose to `[ω, t, ls]` (module doc). Zero after
    /// [`PoseProjection::from_camera_points`], which has no pose chain.
    pub fn pose_gradient(&self, grad_uv: impl Fn(usize) -> DVec2) -> [f64; POSE_DIM] {
        if !self.posed {
            return [0.0; POSE_DIM];
        }
        let q = (self.camera_rotation * self.pose.rotation).transpose();
        let (mut gw, mut gt, mut gs) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
        for i in 0..self.len() {
            let g = grad_uv(i);
            if g == DVec2::ZERO {
                continue;
            }
            let (y, j) = (self.scaled(i), self.jac(i));
            let h = q * (j[0] * g.x + j[1] * g.y);
            gw += y.cross(h);
            gt += h;
            gs += y * h;
        }
        let gt = self.pose.rotation * gt;
        [gw.x, gw.y, gw.z, gt.x, gt.y, gt.z, gs.x, gs.y, gs.z]
    }

    /// As [`PoseProjection::pose_gradient`] for a sparse gradient: `(vertex, ∂L/∂(u, v))`
    /// pairs (each vertex at most once).
    pub fn pose_gradient_sparse(&self, items: impl Iterator<Item = (usize, DVec2)>) -> [f64; POSE_DIM] {
        if !self.posed {
            return [0.0; POSE_DIM];
        }
        let q = (self.camera_rotation * self.pose.rotation).transpose();
        let (mut gw, mut gt, mut gs) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
        for (i, g) in items {
            let (y, j) = (self.scaled(i), self.jac(i));
            let h = q * (j[0] * g.x + j[1] * g.y);
            gw += y.cross(h);
            gt += h;
            gs += y * h;
        }
        let gt = self.pose.rotation * gt;
        [gw.x, gw.y, gw.z, gt.x, gt.y, gt.z, gs.x, gs.y, gs.z]
    }

    /// `∂(u, v)/∂θ` of vertex `i` (rows u, v; the 9 columns `[ω, t, ls]` in lane pairs,
    /// the 10th zero; zero after [`PoseProjection::from_camera_points`]).
    #[inline]
    pub fn vertex_pose_jacobian(&self, i: usize) -> [[f64x2; 5]; 2] {
        if !self.posed {
            return [[f64x2::ZERO; 5]; 2];
        }
        let m = self.camera_rotation * self.pose.rotation;
        let (y, j) = (self.scaled(i), self.jac(i));
        let mut rows = [[0.0; 10]; 2];
        for k in 0..3 {
            let mut e = DVec3::ZERO;
            e[k] = 1.0;
            let cols = [m * e.cross(y), self.camera_rotation * e, m * (e * y)];
            for (g, col) in cols.iter().enumerate() {
                rows[0][3 * g + k] = j[0].dot(*col);
                rows[1][3 * g + k] = j[1].dot(*col);
            }
        }
        rows.map(|r| std::array::from_fn(|c| f64x2::new([r[2 * c], r[2 * c + 1]])))
    }

    /// `∂(u, v)/∂θ` of every vertex (rows u, v; the 9 columns `[ω, t, ls]` in lane
    /// pairs, the 10th zero), written into `out`.
    pub fn vertex_pose_jacobians(&self, out: &mut Vec<[[f64x2; 5]; 2]>) {
        let r = self.pose.rotation;
        let rc = self.camera_rotation;
        let m = rc * r;
        out.clear();
        if !self.posed {
            return;
        }
        for i in 0..self.len() {
            let (y, j) = (self.scaled(i), self.jac(i));
            let mut rows = [[0.0; 10]; 2];
            for k in 0..3 {
                let mut e = DVec3::ZERO;
                e[k] = 1.0;
                let cols = [m * e.cross(y), rc * e, m * (e * y)];
                for (g, col) in cols.iter().enumerate() {
                    rows[0][3 * g + k] = j[0].dot(*col);
                    rows[1][3 * g + k] = j[1].dot(*col);
                }
            }
            out.push(rows.map(|r| std::array::from_fn(|c| f64x2::new([r[2 * c], r[2 * c + 1]]))));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::so3;

    #[test]
    fn pose_gradient_matches_central_differences_of_the_pixels() {
        // L = Σ w_i·(u_i, v_i): its pose gradient from the chain rule vs differences.
        let mesh = crate::app::synth::blob_mesh(4, 6);
        let camera = Camera::look_at(DVec3::new(0.3, -0.2, -4.0), DVec3::ZERO, DVec3::Y, 64, 48, 60.0);
        let pose = Pose {
            rotation: so3::exp(DVec3::new(0.3, 0.1, -0.2)),
            translation: DVec3::new(0.1, -0.05, 0.2),
            scale: DVec3::new(1.1, 0.9, 1.05),
        };
        let w: Vec<DVec2> = (0..mesh.positions.len())
            .map(|i| DVec2::new((i as f64 * 0.7).sin(), (i as f64 * 1.3).cos()))
            .collect();
        let loss = |p: &Pose| -> f64 {
            let pr = project_mesh(&mesh, p, &camera);
            pr.uv.iter().zip(&w).map(|(uv, w)| uv.dot(*w)).sum()
        };
        let mut pp = PoseProjection::default();
        pp.project(&mesh, &pose, &camera);
        let g = pp.pose_gradient(|i| w[i]);
        let mut jac = Vec::new();
        pp.vertex_pose_jacobians(&mut jac);
        let h = 1e-6;
        for k in 0..POSE_DIM {
            let mut e = DVec3::ZERO;
            e[k % 3] = h;
            let step = |sgn: f64| match k / 3 {
                0 => Pose {
                    rotation: pose.rotation * so3::exp(e * sgn),
                    ..pose
                },
                1 => Pose {
                    translation: pose.translation + e * sgn,
                    ..pose
                },
                _ => Pose {
                    scale: pose.scale * (e * sgn).exp(),
                    ..pose
                },
            };
            let fd = (loss(&step(1.0)) - loss(&step(-1.0))) / (2.0 * h);
            assert!(
                (fd - g[k]).abs() < 1e-5 * g[k].abs().max(1.0),
                "parameter {k}: {} vs {fd}",
                g[k]
            );
            // The forward-mode Jacobians give the same directional derivative.
            let fwd: f64 = jac
                .iter()
                .zip(&w)
                .map(|(rows, w)| w.x * rows[0][k / 2].to_array()[k % 2] + w.y * rows[1][k / 2].to_array()[k % 2])
                .sum();
            assert!((fwd - g[k]).abs() < 1e-9 * g[k].abs().max(1.0));
        }
    }
}
