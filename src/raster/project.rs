//! Projection of a posed mesh into a view: model → world (pose) → camera (OpenCV)
//! → pixels (SPEC §2). Shared by the hard and soft rasterisers.

use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::mesh::Mesh;
use crate::pose::Pose;
use glam::{DVec2, DVec3};

/// A mesh's vertices in one camera.
#[derive(Debug, Clone, Default)]
pub struct Projected {
    /// Camera-frame positions (OpenCV axes).
    pub cam: Vec<DVec3>,
    /// Pixel coordinates; meaningful only where `cam[i].z >= near`.
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

/// The near-plane depth for a camera: a tiny fraction of the focal length's pixel
/// footprint, so that only points essentially at or behind the camera centre are cut.
pub fn near_plane(mesh_extent: f64) -> f64 {
    (mesh_extent * 1e-4).max(1e-9)
}

/// Projects every vertex of `mesh` under `pose` into `camera`.
pub fn project_mesh(mesh: &Mesh, pose: &Pose, camera: &Camera) -> Projected {
    let cam: Vec<DVec3> = mesh
        .positions
        .iter()
        .map(|p| camera.to_camera(pose.apply(*p)))
        .collect();
    let extent = mesh
        .bounds()
        .map(|b| (b.size() * pose.scale.abs()).length())
        .unwrap_or(1.0);
    let near = near_plane(extent);
    let uv = cam
        .iter()
        .map(|c| {
            if c.z >= near {
                camera.project(*c)
            } else {
                DVec2::splat(f64::NAN)
            }
        })
        .collect();
    Projected { cam, uv, near }
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
