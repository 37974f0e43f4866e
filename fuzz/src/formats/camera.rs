//! Cameras, poses and grasps: their specs and JSON, and the camera driver.

use super::{check_camera, dump, num, nums, rows3, rows4};
use localisebot::Camera;

// ---------------------------------------------------------------------------------
// Cameras, poses, grasps

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CamKey {
    W2c,
    C2w,
    Both,
    Neither,
}

/// A camera as `scene.json` writes it; `width`, `height` may be out of any range.
#[derive(Debug, Clone, PartialEq)]
pub struct CamSpec {
    pub width: i64,
    pub height: i64,
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
    pub matrix: [[f64; 4]; 4],
    pub key: CamKey,
    pub opengl: bool,
}

pub fn camera_json(c: &CamSpec) -> String {
    let mut s = format!(
        "{{\"width\": {}, \"height\": {}, \"fx\": {}, \"fy\": {}, \"cx\": {}, \"cy\": {}",
        c.width,
        c.height,
        num(c.fx),
        num(c.fy),
        num(c.cx),
        num(c.cy)
    );
    let m = rows4(&c.matrix);
    match c.key {
        CamKey::W2c => s += &format!(", \"world_to_camera\": {m}"),
        CamKey::C2w => s += &format!(", \"camera_to_world\": {m}"),
        CamKey::Both => s += &format!(", \"world_to_camera\": {m}, \"camera_to_world\": {m}"),
        CamKey::Neither => {}
    }
    if c.opengl {
        s += ", \"convention\": \"opengl\"";
    }
    s + "}"
}

/// Parses a camera as the readers do and converts it; checks an accepted camera.
pub fn drive_camera(text: &str) -> localisebot::Result<Camera> {
    dump("camera.json", text.as_bytes());
    let cj: localisebot::CameraJson = serde_json::from_str(text).map_err(|e| localisebot::Error::Json {
        file: "camera.json".into(),
        problem: e.to_string(),
    })?;
    let r = cj.to_camera_with_warning("v").map(|(c, _)| c);
    if let Ok(c) = &r {
        check_camera(c);
    }
    r
}

#[derive(Debug, Clone, PartialEq)]
pub enum RotSpec {
    Matrix([[f64; 3]; 3]),
    Quaternion([f64; 4]),
    /// Under the `quaternion` key.
    QuaternionKey([f64; 4]),
}

#[derive(Debug, Clone, PartialEq)]
pub struct PoseSpec {
    pub rotation: RotSpec,
    pub translation: [f64; 3],
    pub scale: Option<[f64; 3]>,
}

pub fn pose_json(p: &PoseSpec) -> String {
    let mut s = match &p.rotation {
        RotSpec::Matrix(m) => format!("{{\"rotation\": {}", rows3(m)),
        RotSpec::Quaternion(q) => format!("{{\"rotation\": {}", nums(q)),
        RotSpec::QuaternionKey(q) => format!("{{\"quaternion\": {}", nums(q)),
    };
    s += &format!(", \"translation\": {}", nums(&p.translation));
    if let Some(sc) = p.scale {
        s += &format!(", \"scale\": {}", nums(&sc));
    }
    s + "}"
}

#[derive(Debug, Clone, PartialEq)]
pub struct GraspSpec {
    pub centre: [f64; 3],
    pub approach: [f64; 3],
    pub closing: [f64; 3],
    pub width: f64,
    pub depth: f64,
    pub score: Option<f64>,
}

pub fn grasp_json(g: &GraspSpec) -> String {
    let mut s = format!(
        "{{\"centre\": {}, \"approach\": {}, \"closing\": {}, \"width\": {}, \"depth\": {}",
        nums(&g.centre),
        nums(&g.approach),
        nums(&g.closing),
        num(g.width),
        num(g.depth)
    );
    if let Some(v) = g.score {
        s += &format!(", \"score\": {}", num(v));
    }
    s + "}"
}
