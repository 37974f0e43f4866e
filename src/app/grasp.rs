//! Parallel-jaw grasps: defined on the object, carried to the world with a pose and
//! projected into a camera as a 2-D grasp rectangle (OCID/Cornell form), so that a
//! grasp transferred with the estimated pose can be scored against the same grasp
//! under the true pose (SPEC §6, the paper's Table 3).
//!
//! Inputs: a [`Grasp`] in the model frame (model units), a [`Pose`] and a [`Camera`];
//! outputs: a [`WorldGrasp`] (world units) and a rectangle `[DVec2; 4]` in pixels.
//! The grasp's JSON form and its validation are in [`crate::io::grasp`].
//! Submodules: [`rect`] (angle, polygon IoU, the correctness test, the `.txt` format;
//! after `calc_jacc_IOU` / `prepare_frcnn_format` of grasp_det_seg_cnn, FORMATS.md §5)
//! and [`antipodal`] (antipodal grasp candidates sampled on a closed mesh).
//!
//! **Pose and per-axis scale.** A grasp is the three model points it defines: the
//! contacts `c ± (width/2)·closing` and the palm point `c − depth·approach`. A pose
//! maps them as model points (`X ↦ R·(s⊙X) + t`). In the world, `centre` is the
//! contacts' midpoint (= the mapped centre), `closing` and `width` are the direction
//! and length of the mapped contact-to-contact segment (so `width` scales by
//! `|s⊙closing|`), and `approach` and `depth` are the direction and length of the part
//! of the mapped palm-to-centre segment perpendicular to the world `closing` (so
//! `depth` scales by `|s⊙approach|` up to the shear a non-uniform scale introduces,
//! and the world frame stays orthonormal). The inverse map ([`WorldGrasp::to_object`])
//! applies the same rule and recovers the model grasp exactly.
//!
//! **Rectangle.** [`grasp_rectangle`] projects the planar rectangle centred on the
//! grasp, with edge p0→p1 along `closing` of length `width` (the jaw opening, as
//! `width = |p0p1|` in FORMATS.md) and edge p1→p2 along `approach × closing` of length
//! [`JAW_FRACTION`]`·width` (the finger plates' breadth); p1p2 and p3p0 are the jaws.

pub mod antipodal;
pub mod rect;

pub use antipodal::{antipodal_grasps, ANTIPODAL_CLEARANCE, ANTIPODAL_CONE_DEG, ANTIPODAL_DEPTH_FRACTION};
pub use rect::{
    angle_difference_deg, grasp_correct, rectangle_angle_deg, rectangle_area, rectangle_iou, rectangles_from_txt,
    rectangles_to_txt, ANGLE_TOLERANCE_DEG, IOU_THRESHOLD,
};

use crate::app::overlay::draw_line;
use crate::camera::Camera;
pub use crate::io::grasp::{grasps_from_json, Grasp, GraspJson};
use crate::pose::Pose;
use crate::view::Rgba;
use glam::{DVec2, DVec3};

/// The breadth of the finger plates (the rectangle's p1p2 edge) as a fraction of the opening.
pub const JAW_FRACTION: f64 = 0.5;

/// Smallest camera depth of a rectangle corner that still projects.
const MIN_DEPTH: f64 = 1e-9;

impl Grasp {
    /// The grasp in the world under `pose` (the point rule of the module docs).
    pub fn to_world(&self, pose: &Pose) -> WorldGrasp {
        let (centre, approach, closing, width, depth) =
            map_frame(self.centre, self.approach, self.closing, self.width, self.depth, |p| {
                pose.apply(p)
            });
        WorldGrasp {
            centre,
            approach,
            closing,
            width,
            depth,
        }
    }
}

/// Maps a grasp's contacts and palm point through `map` and rebuilds the frame
/// (module docs). Returns (centre, approach, closing, width, depth).
fn map_frame(
    centre: DVec3,
    approach: DVec3,
    closing: DVec3,
    width: f64,
    depth: f64,
    map: impl Fn(DVec3) -> DVec3,
) -> (DVec3, DVec3, DVec3, f64, f64) {
    let h = 0.5 * width * closing;
    let (a, b) = (map(centre - h), map(centre + h));
    let palm = map(centre - depth * approach);
    let c = 0.5 * (a + b);
    let span = b - a;
    let width = span.length();
    let closing = span / width;
    let reach = c - palm;
    let perp = reach - reach.dot(closing) * closing;
    let depth = perp.length();
    (c, perp / depth, closing, width, depth)
}

/// A grasp carried to the world (world units); `approach` and `closing` orthonormal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WorldGrasp {
    /// Midpoint between the finger contacts.
    pub centre: DVec3,
    /// Unit direction the gripper moves along to reach the object.
    pub approach: DVec3,
    /// Unit direction the fingers close along.
    pub closing: DVec3,
    /// Opening between the fingers.
    pub width: f64,
    /// Finger depth along `approach`.
    pub depth: f64,
}

impl WorldGrasp {
    /// The two finger contacts `centre ∓ (width/2)·closing`.
    pub fn contacts(&self) -> [DVec3; 2] {
        let h = 0.5 * self.width * self.closing;
        [self.centre - h, self.centre + h]
    }

    /// Back to the object frame of `pose` (the inverse of [`Grasp::to_world`]:
    /// `X_o = (Rᵀ(X_w − t)) ⊘ s`, same point rule). `pose` must be valid (scale > 0);
    /// the result carries no score.
    pub fn to_object(&self, pose: &Pose) -> Grasp {
        let rt = pose.rotation.transpose();
        let (centre, approach, closing, width, depth) =
            map_frame(self.centre, self.approach, self.closing, self.width, self.depth, |p| {
                rt * (p - pose.translation) / pose.scale
            });
        Grasp {
            centre,
            approach,
            closing,
            width,
            depth,
            score: None,
        }
    }

    /// The rectangle's corners in the world, in the order of [`grasp_rectangle`].
    pub fn rectangle_corners(&self) -> [DVec3; 4] {
        let k = 0.5 * self.width * self.closing;
        let j = 0.5 * JAW_FRACTION * self.width * self.approach.cross(self.closing);
        [
            self.centre - k - j,
            self.centre + k - j,
            self.centre + k + j,
            self.centre - k + j,
        ]
    }
}

/// The grasp's 2-D rectangle in `camera`'s pixels (OpenCV, pixel centres at integers):
/// the world rectangle centred on the grasp with p0→p1 along `closing` (length
/// `width`: the opening) and p1→p2 along `approach × closing` (length
/// [`JAW_FRACTION`]`·width`: the jaws), each corner projected. `None` when a corner is
/// not in front of the camera. A grasp whose approach is perpendicular to the line of
/// sight projects to a thin or degenerate rectangle (see [`rectangle_area`]).
pub fn grasp_rectangle(grasp: &WorldGrasp, camera: &Camera) -> Option<[DVec2; 4]> {
    let mut out = [DVec2::ZERO; 4];
    for (o, p) in out.iter_mut().zip(grasp.rectangle_corners()) {
        let pc = camera.to_camera(p);
        if pc.z.is_nan() || pc.z <= MIN_DEPTH {
            return None;
        }
        *o = camera.project(pc);
    }
    Some(out)
}

/// Whether `grasp`, carried to the world with the `estimated` pose and projected into
/// `camera`, is correct against the same grasp under the `truth` pose ([`grasp_correct`]).
/// `None` when the true rectangle does not project (the view cannot judge the grasp);
/// `Some(false)` when only the estimated one does not.
pub fn grasp_transfer_correct(grasp: &Grasp, estimated: &Pose, truth: &Pose, camera: &Camera) -> Option<bool> {
    let gt = grasp_rectangle(&grasp.to_world(truth), camera)?;
    Some(grasp_rectangle(&grasp.to_world(estimated), camera).is_some_and(|est| grasp_correct(&est, &gt)))
}

/// Draws a grasp rectangle as in Cornell visualisations: the jaw edges (p1p2, p3p0)
/// 2 px wide in `colour`, the opening edges (p0p1, p2p3) 1 px in `colour` at half
/// intensity (alpha kept). Clipped to the image; non-finite corners draw nothing.
pub fn draw_grasp(img: &mut Rgba, rect: &[DVec2; 4], colour: [u8; 4]) {
    let dim = [colour[0] / 2, colour[1] / 2, colour[2] / 2, colour[3]];
    draw_line(img, rect[0], rect[1], dim);
    draw_line(img, rect[2], rect[3], dim);
    for (a, b) in [(rect[1], rect[2]), (rect[3], rect[0])] {
        draw_line(img, a, b, colour);
        let d = b - a;
        let len = d.length();
        if len > 0.0 && len.is_finite() {
            // A parallel line one pixel over, on the outside of the rectangle.
            let centre = 0.25 * (rect[0] + rect[1] + rect[2] + rect[3]);
            let mut off = d.perp() / len;
            if off.dot(a - centre) < 0.0 {
                off = -off;
            }
            draw_line(img, a + off, b + off, colour);
        }
    }
}

/// The 2-D rectangles of `grasps` transferred with `pose` into `camera` (grasps
/// behind the camera left out).
pub fn rectangles(grasps: &[Grasp], pose: &Pose, camera: &Camera) -> Vec<[DVec2; 4]> {
    grasps
        .iter()
        .filter_map(|g| grasp_rectangle(&g.to_world(pose), camera))
        .collect()
}

/// Draws `grasps`, transferred with `pose` into `camera`, over an overlay (cyan).
pub fn draw_grasps(img: &mut Rgba, grasps: &[Grasp], pose: &Pose, camera: &Camera) {
    for r in rectangles(grasps, pose, camera) {
        draw_grasp(img, &r, [0, 220, 255, 255]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::so3;

    fn pose() -> Pose {
        Pose {
            rotation: so3::exp(DVec3::new(0.3, -0.8, 0.5)),
            translation: DVec3::new(0.2, -1.0, 3.0),
            scale: DVec3::new(0.5, 1.5, 2.0),
        }
    }

    #[test]
    fn validation_normalises_and_orthogonalises() {
        let a = DVec3::new(0.0, 0.02, -1.0).normalize() * 1.005;
        let g = Grasp::new(DVec3::ZERO, a, DVec3::X, 1.0, 0.5).unwrap();
        assert!((g.approach.length() - 1.0).abs() < 1e-12);
        assert!(g.approach.dot(g.closing).abs() < 1e-12);
        assert!((g.approach - DVec3::new(0.0, 0.02, -1.0).normalize()).length() < 1e-12);
        let e = Grasp::new(DVec3::ZERO, DVec3::Z, DVec3::new(1.0, 0.0, 0.2).normalize(), 1.0, 0.5);
        assert!(e.unwrap_err().to_string().contains("perpendicular"));
        let e = Grasp::new(DVec3::ZERO, DVec3::Z * 2.0, DVec3::X, 1.0, 0.5);
        assert!(e.unwrap_err().to_string().contains("approach must be a unit vector"));
    }

    #[test]
    fn world_frame_follows_the_point_rule() {
        let g = Grasp::new(DVec3::new(0.1, 0.2, 0.3), DVec3::Z, DVec3::X, 0.4, 0.2).unwrap();
        let p = pose();
        let w = g.to_world(&p);
        let [a, b] = w.contacts();
        let [ma, mb] = g.contacts();
        assert!((a - p.apply(ma)).length() < 1e-12 && (b - p.apply(mb)).length() < 1e-12);
        // Axis-aligned directions: width scales by s_x, depth by s_z exactly.
        assert!((w.width - 0.4 * 0.5).abs() < 1e-12);
        assert!((w.depth - 0.2 * 2.0).abs() < 1e-12);
        assert!((w.approach - p.rotation * DVec3::Z).length() < 1e-12);
    }

    #[test]
    fn json_round_trip_and_serde_validate() {
        let mut g = Grasp::new(DVec3::new(1.0, 2.0, 3.0), DVec3::Y, -DVec3::Z, 0.3, 0.1).unwrap();
        g.score = Some(0.75);
        let back = Grasp::from_json(&g.to_json()).unwrap();
        assert_eq!(back, g);
        let via_serde: Grasp = serde_json::from_value(serde_json::to_value(g).unwrap()).unwrap();
        assert_eq!(via_serde, g);
        let bad = serde_json::json!({"centre":[0,0,0],"approach":[0,0,1],"closing":[1,0,0],"width":0,"depth":1});
        assert!(serde_json::from_value::<Grasp>(bad)
            .unwrap_err()
            .to_string()
            .contains("width must be positive"));
    }
}
