//! The geometry of the page's 3D view (`www/view3d.js` only draws it): each camera's
//! frame in the world — its centre, its axes and its camera-to-world matrix, the
//! corners of its image plane at a depth for the frustum — and where the view looks
//! from: the point nearest every camera's optical axis (least squares), the orbit's up
//! (minus the cameras' mean y axis, OpenCV's y pointing down in the image) and a
//! viewer that sees every camera and the object.

use crate::camera::Camera;
use crate::mesh::Mesh;
use glam::{DMat4, DVec3, DVec4};

/// The image planes' depth as a fraction of the cameras' median distance to the target.
pub const DEPTH_FRACTION: f64 = 0.3;

/// The 3D viewer's vertical field of view, degrees.
pub const VIEWER_FOV_DEG: f64 = 45.0;

/// A camera's frame in the world (OpenCV axes: x right, y down, z forward).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraFrame {
    /// The camera's centre.
    pub centre: DVec3,
    /// Its x, y and z axes (unit), world coordinates.
    pub axes: [DVec3; 3],
    /// Camera to world, `[Rᵀ | centre]`.
    pub camera_to_world: DMat4,
}

impl CameraFrame {
    /// The frame of `camera`.
    pub fn new(camera: &Camera) -> CameraFrame {
        let rt = camera.rotation.transpose();
        let centre = camera.centre();
        CameraFrame {
            centre,
            axes: [rt.x_axis, rt.y_axis, rt.z_axis],
            camera_to_world: DMat4::from_cols(
                rt.x_axis.extend(0.0),
                rt.y_axis.extend(0.0),
                rt.z_axis.extend(0.0),
                centre.extend(1.0),
            ),
        }
    }

    /// The optical axis (z, forward).
    pub fn forward(&self) -> DVec3 {
        self.axes[2]
    }

    /// Camera to world for a viewer with OpenGL's axes (x right, y up, looking down −z):
    /// the camera's frame with y and z negated, for looking through it.
    pub fn viewer_to_world(&self) -> DMat4 {
        self.camera_to_world * DMat4::from_diagonal(DVec4::new(1.0, -1.0, -1.0, 1.0))
    }
}

/// The frustum of `camera` in its own frame with the image plane at `depth`: the
/// plane's corners at the pixel edges (u from −½ to width − ½), top-left, top-right,
/// bottom-right, bottom-left; and a small triangle over the top edge (left foot, tip,
/// right foot) that tells the image's up.
pub fn frustum(camera: &Camera, depth: f64) -> ([DVec3; 4], [DVec3; 3]) {
    let corner = |u: f64, v: f64| {
        DVec3::new(
            (u - camera.cx) / camera.fx * depth,
            (v - camera.cy) / camera.fy * depth,
            depth,
        )
    };
    let (u0, u1) = (-0.5, camera.width as f64 - 0.5);
    let (v0, v1) = (-0.5, camera.height as f64 - 0.5);
    let c = [corner(u0, v0), corner(u1, v0), corner(u1, v1), corner(u0, v1)];
    let mid = (c[0] + c[1]) * 0.5;
    let tip = mid - DVec3::new(0.0, 0.25 * (c[3].y - c[0].y), 0.0); // up in the image is −y
    let half = DVec3::new(0.15 * (c[1].x - c[0].x), 0.0, 0.0);
    (c, [mid - half, tip, mid + half])
}

/// The point nearest every frame's optical axis (least squares: `Σ (I − d dᵀ)(x − c) =
/// 0`), or `None` for fewer than two frames or axes (nearly) parallel.
pub fn axes_meet(frames: &[CameraFrame]) -> Option<DVec3> {
    let rays: Vec<_> = frames.iter().map(|f| (f.centre, f.forward().normalize())).collect();
    crate::optim::init::nearest_point(&rays)
}

/// The orbit's up: minus the frames' mean y axis (unit), or world z when that vanishes.
pub fn orbit_up(frames: &[CameraFrame]) -> DVec3 {
    let up = -frames.iter().map(|f| f.axes[1]).sum::<DVec3>();
    if up.length() < 1e-6 * frames.len().max(1) as f64 {
        DVec3::Z
    } else {
        up.normalize()
    }
}

/// The radius of a mesh's bounding ball about its box's centre (as three.js's
/// `computeBoundingSphere`); 0 for an empty mesh.
pub fn bounding_radius(mesh: &Mesh) -> f64 {
    let Some(b) = mesh.bounds() else { return 0.0 };
    let c = b.centre();
    mesh.positions.iter().map(|p| p.distance(c)).fold(0.0, f64::max)
}

/// Where the 3D viewer starts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Viewer {
    /// Its position, looking at the scene's target with the orbit's up.
    pub position: DVec3,
    /// Its clipping planes.
    pub near: f64,
    /// Far clipping plane.
    pub far: f64,
    /// Its vertical field of view, degrees.
    pub fov_deg: f64,
}

/// The 3D view's scene: every camera's frame, where they look, the orbit's up, the
/// image planes' depth and the viewer's start.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneFrames {
    /// One frame per camera, in order.
    pub frames: Vec<CameraFrame>,
    /// The axes' meeting point ([`axes_meet`]), when they meet.
    pub meet: Option<DVec3>,
    /// Where the cameras look: the meeting point, else in front of their centroid.
    pub target: DVec3,
    /// The orbit's up ([`orbit_up`]).
    pub up: DVec3,
    /// The image planes' depth: [`DEPTH_FRACTION`] of the cameras' median distance to the target.
    pub depth: f64,
    /// The viewer's start: from above the cameras' side, just far enough to see every
    /// camera, its image plane and a ball of `radius` about the target.
    pub home: Viewer,
}

impl SceneFrames {
    /// The scene of `cameras` around an object of bounding radius `radius` (model
    /// frame), for a viewer of [`VIEWER_FOV_DEG`] and width/height `aspect`.
    pub fn new(cameras: &[Camera], radius: f64, aspect: f64) -> SceneFrames {
        let frames: Vec<CameraFrame> = cameras.iter().map(CameraFrame::new).collect();
        let radius = if radius.is_finite() && radius > 0.0 {
            radius
        } else {
            1.0
        };
        let aspect = if aspect.is_finite() && aspect > 0.0 {
            aspect
        } else {
            1.0
        };
        let n = frames.len().max(1) as f64;
        let centroid = frames.iter().map(|f| f.centre).sum::<DVec3>() / n;
        let mean_axis = frames.iter().map(|f| f.forward()).sum::<DVec3>().normalize_or_zero();
        let spread = frames.iter().map(|f| f.centre.distance(centroid)).fold(0.0, f64::max);
        let meet = axes_meet(&frames);
        let target = meet.unwrap_or(centroid + mean_axis * spread.max(4.0 * radius));
        let mut dists: Vec<f64> = frames.iter().map(|f| f.centre.distance(target)).collect();
        dists.sort_by(f64::total_cmp);
        let dist = dists.get(dists.len() / 2).copied().unwrap_or(4.0 * radius);
        let dist = if dist > 0.0 { dist } else { 1.0 };
        let depth = DEPTH_FRACTION * dist;
        let up = orbit_up(&frames);

        // Above the cameras' side: each point p needs a distance D ≥ along + lateral /
        // tan(half-angle).
        let mut side = centroid - target;
        side -= up * side.dot(up);
        if side.length() < 1e-9 * dist {
            side = up.cross(if up.x.abs() < 0.9 { DVec3::X } else { DVec3::Y });
        }
        let dir = (side.normalize() + up * 0.8).normalize();
        let right = (-dir).cross(up).normalize();
        let up_view = right.cross(-dir);
        let tan_v = (VIEWER_FOV_DEG.to_radians() / 2.0).tan();
        let tan_h = tan_v * aspect;
        let mut points: Vec<DVec3> = frames
            .iter()
            .flat_map(|f| [f.centre, f.centre + f.forward() * depth])
            .collect();
        for a in [right, up_view, dir] {
            points.extend([target + a * radius, target - a * radius]);
        }
        let range = 1.1
            * points
                .iter()
                .map(|&p| {
                    let q = p - target;
                    q.dot(dir) + (q.dot(right).abs() / tan_h).max(q.dot(up_view).abs() / tan_v)
                })
                .fold(f64::MIN, f64::max);
        SceneFrames {
            frames,
            meet,
            target,
            up,
            depth,
            home: Viewer {
                position: target + dir * range,
                near: range / 1000.0,
                far: range * 20.0,
                fov_deg: VIEWER_FOV_DEG,
            },
        }
    }

    /// Where the viewer looking through camera `i` orbits: on its axis, at the
    /// target's distance.
    pub fn look_target(&self, i: usize) -> DVec3 {
        let f = &self.frames[i];
        f.centre + f.forward() * f.centre.distance(self.target).max(1e-9)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ring(target: DVec3, n: usize) -> Vec<Camera> {
        (0..n)
            .map(|k| {
                let a = k as f64 * std::f64::consts::TAU / n as f64;
                let eye = target + DVec3::new(3.0 * a.cos(), 3.0 * a.sin(), 1.0 + 0.3 * k as f64);
                Camera::look_at(eye, target, DVec3::Z, 64, 48, 60.0)
            })
            .collect()
    }

    #[test]
    fn a_frame_is_the_cameras_inverse() {
        let cam = ring(DVec3::new(0.2, -0.1, 0.4), 3)[1];
        let f = CameraFrame::new(&cam);
        assert!(f.centre.abs_diff_eq(cam.centre(), 1e-12));
        assert!((f.camera_to_world * cam.world_to_camera_matrix()).abs_diff_eq(DMat4::IDENTITY, 1e-12));
        // Its axes are the camera's rows; z points at the target.
        assert!(f.forward().abs_diff_eq(cam.rotation.row(2), 1e-15));
        assert!(f.forward().dot((DVec3::new(0.2, -0.1, 0.4) - f.centre).normalize()) > 1.0 - 1e-12);
        // The viewer looks down −z: its −z is the camera's forward, its y the image's up.
        let v = f.viewer_to_world();
        assert!((-v.z_axis.truncate()).abs_diff_eq(f.forward(), 1e-15));
        assert!(v.y_axis.truncate().abs_diff_eq(-f.axes[1], 1e-15));
        // The frustum's corners project to the image's pixel edges.
        let (c, marker) = frustum(&cam, 2.0);
        let uv = cam.project(c[2]);
        assert!((uv.x - 63.5).abs() < 1e-9 && (uv.y - 47.5).abs() < 1e-9, "{uv}");
        assert!(c.iter().all(|p| p.z == 2.0));
        assert!(marker[1].y < c[0].y, "the marker's tip is above the top edge");
    }

    #[test]
    fn the_axes_of_cameras_looking_at_a_point_meet_there() {
        let target = DVec3::new(0.5, -1.0, 2.0);
        let frames: Vec<CameraFrame> = ring(target, 4).iter().map(CameraFrame::new).collect();
        let meet = axes_meet(&frames).unwrap();
        assert!(meet.abs_diff_eq(target, 1e-9), "{meet}");
        // Two cameras looking at the point from different sides: still that point.
        assert!(axes_meet(&frames[..2]).unwrap().abs_diff_eq(target, 1e-9));
        // One camera, or parallel axes: none.
        assert_eq!(axes_meet(&frames[..1]), None);
        let a = Camera::look_at(DVec3::ZERO, DVec3::Z, DVec3::Y, 64, 48, 60.0);
        let b = Camera::look_at(DVec3::X, DVec3::X + DVec3::Z, DVec3::Y, 64, 48, 60.0);
        assert_eq!(axes_meet(&[CameraFrame::new(&a), CameraFrame::new(&b)]), None);
    }

    #[test]
    fn the_scene_looks_at_the_meeting_point_from_above_and_sees_every_camera() {
        let target = DVec3::new(0.5, -1.0, 2.0);
        let cams = ring(target, 4);
        let s = SceneFrames::new(&cams, 0.5, 1.5);
        assert!(s.target.abs_diff_eq(target, 1e-9));
        assert_eq!(s.meet, Some(s.target));
        // Image-up is world z for these cameras: the orbit's up too.
        assert!(s.up.z > 0.9, "{}", s.up);
        assert!((s.up.length() - 1.0).abs() < 1e-12);
        let median = {
            let mut d: Vec<f64> = cams.iter().map(|c| c.centre().distance(target)).collect();
            d.sort_by(f64::total_cmp);
            d[2]
        };
        assert!((s.depth - 0.3 * median).abs() < 1e-9);
        // The viewer is above the cameras, farther than any of them, and every camera's
        // centre is within its field of view.
        let eye = s.home.position;
        assert!((eye - target).dot(s.up) > 0.0);
        let back = (target - eye).normalize();
        let half = (VIEWER_FOV_DEG.to_radians() / 2.0).cos();
        for c in &cams {
            assert!(
                (c.centre() - eye).normalize().dot(back) > half * 0.9,
                "camera out of sight"
            );
        }
        assert!(s.home.near > 0.0 && s.home.far > 10.0 * eye.distance(target));
        let look = s.look_target(1);
        assert!(look.abs_diff_eq(target, 1e-9), "{look}");
    }

    #[test]
    fn the_bounding_radius_reaches_the_farthest_vertex() {
        let cube = Mesh::cuboid(DVec3::new(2.0, 2.0, 2.0));
        assert!((bounding_radius(&cube) - 3f64.sqrt()).abs() < 1e-12);
        assert_eq!(
            bounding_radius(&Mesh {
                positions: vec![],
                triangles: vec![]
            }),
            0.0
        );
    }

    #[test]
    fn one_camera_looks_in_front_of_itself() {
        let cam = Camera::look_at(DVec3::ZERO, DVec3::Z, DVec3::Y, 64, 48, 60.0);
        let s = SceneFrames::new(&[cam], 0.25, 1.0);
        assert_eq!(s.meet, None);
        assert!(s.target.abs_diff_eq(DVec3::Z, 1e-12), "4 radii ahead: {}", s.target);
        assert!(s.home.position.is_finite());
        let none = SceneFrames::new(&[], 1.0, 1.0);
        assert!(none.frames.is_empty() && none.target.is_finite() && none.home.position.is_finite());
    }
}
