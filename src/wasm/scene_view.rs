//! What the page's 3D view draws (`www/view3d.js`, which only draws): a second
//! `#[wasm_bindgen] impl Session` block with the mesh for display, each view's camera
//! in scene-file form, a picture of each view (its photograph, or its mask) for the
//! image planes, the cameras' frames and where the viewer looks from
//! (`cameraFrames`, `crate::app::scene_view`), and the ghosts of a finished fit
//! (`ghosts`, poses drawn from its covariance, `uncertainty::ghost_poses`); and
//! `framesOfCameras`, the frames of any cameras (the suggested next views). No maths
//! here beyond capping sizes for display.

use super::{to_js, Session};
use crate::app::scene_view::{bounding_radius, frustum, CameraFrame, SceneFrames};
use crate::camera::{Camera, CameraJson};
use crate::mesh::Mesh;
use crate::pose::mat4_to_rows;
use crate::uncertainty::ghost_poses;
use crate::view::View;
use glam::DVec3;
use serde::Serialize;
use wasm_bindgen::prelude::*;

/// Above this many triangles the display mesh is a vertex-clustered copy
/// ([`Mesh::clustered`]) of at most this many: the 3D view is a picture, and a browser
/// draws 200k triangles without trouble.
pub const MAX_DISPLAY_TRIANGLES: usize = 200_000;

/// Largest side of a view's picture for the 3D view's image planes, by default.
pub const DEFAULT_PICTURE_SIDE: u32 = 512;

#[wasm_bindgen(typescript_custom_section)]
const TS_SCENE_VIEW: &'static str = r#"
/** The mesh as the 3D view draws it: model frame, xyz per vertex, three indices per triangle. */
export interface DisplayGeometry {
  positions: Float32Array; indices: Uint32Array;
  /** Triangles drawn, and in the fitted mesh (more when the display copy was decimated). */
  triangles: number; source_triangles: number; decimated: boolean;
}
/** A view's camera in scene-file form (SPEC §3): OpenCV axes, `world_to_camera` 4×4 row-major. */
export interface SceneCamera {
  name: string; width: number; height: number; fx: number; fy: number; cx: number; cy: number;
  world_to_camera: number[][];
}
/** A view's picture for the 3D view: RGBA8, row 0 at the top, at most `maxSide` pixels a side. */
export interface ViewPicture {
  width: number; height: number; kind: "image" | "mask"; rgba: Uint8ClampedArray;
}
/** A camera's frame in the world (OpenCV axes: x right, y down, z forward), for drawing its frustum. */
export interface CameraFrame {
  /** Its centre and its x, y, z axes (unit), world coordinates. */
  centre: number[]; x: number[]; y: number[]; z: number[];
  /** Camera to world, 4×4 rows; the same for a viewer with OpenGL's axes (y and z negated), to look through it. */
  camera_to_world: number[][]; viewer_to_world: number[][];
  /** The image plane at the scene's depth, camera frame: its corners at the pixel edges (top-left, top-right, bottom-right, bottom-left), and the triangle over its top edge (left foot, tip, right foot). */
  corners: number[][]; marker: number[][];
  /** For a view's camera: where a viewer looking through it orbits (on its axis, at the target's distance). */
  look_at?: number[];
}
/** The 3D view's scene: the views' camera frames, where they look and the viewer's start. */
export interface SceneFrames {
  frames: CameraFrame[];
  /** The point nearest every camera's optical axis (least squares), or null when they are (nearly) parallel or fewer than two. */
  meet: number[] | null;
  /** Where the cameras look: `meet`, else in front of their centroid. */
  target: number[];
  /** The orbit's up: minus the cameras' mean y axis (unit). */
  up: number[];
  /** The image planes' depth (30 % of the cameras' median distance to the target), scene units. */
  depth: number;
  /** The viewer's start: position (looking at `target`), clipping planes and vertical field of view (degrees). */
  home: { position: number[]; near: number; far: number; fov_deg: number };
}
"#;

/// A camera as `cameras()` returns it.
#[derive(Serialize)]
struct SceneCamera<'a> {
    name: &'a str,
    width: u32,
    height: u32,
    fx: f64,
    fy: f64,
    cx: f64,
    cy: f64,
    world_to_camera: [[f64; 4]; 4],
}

impl<'a> SceneCamera<'a> {
    fn new(name: &'a str, c: &Camera) -> Self {
        SceneCamera {
            name,
            width: c.width,
            height: c.height,
            fx: c.fx,
            fy: c.fy,
            cx: c.cx,
            cy: c.cy,
            world_to_camera: mat4_to_rows(c.world_to_camera_matrix()),
        }
    }
}

/// A camera's frame as the 3D view takes it.
#[derive(Serialize)]
struct FrameOut {
    centre: [f64; 3],
    x: [f64; 3],
    y: [f64; 3],
    z: [f64; 3],
    camera_to_world: [[f64; 4]; 4],
    viewer_to_world: [[f64; 4]; 4],
    corners: [[f64; 3]; 4],
    marker: [[f64; 3]; 3],
    #[serde(skip_serializing_if = "Option::is_none")]
    look_at: Option<[f64; 3]>,
}

impl FrameOut {
    fn new(camera: &Camera, frame: &CameraFrame, depth: f64, look_at: Option<DVec3>) -> FrameOut {
        let (corners, marker) = frustum(camera, depth);
        let [x, y, z] = frame.axes.map(|v| v.to_array());
        FrameOut {
            centre: frame.centre.to_array(),
            x,
            y,
            z,
            camera_to_world: mat4_to_rows(frame.camera_to_world),
            viewer_to_world: mat4_to_rows(frame.viewer_to_world()),
            corners: corners.map(|v| v.to_array()),
            marker: marker.map(|v| v.to_array()),
            look_at: look_at.map(|v| v.to_array()),
        }
    }
}

#[derive(Serialize)]
struct ViewerOut {
    position: [f64; 3],
    near: f64,
    far: f64,
    fov_deg: f64,
}

#[derive(Serialize)]
struct SceneFramesOut {
    frames: Vec<FrameOut>,
    meet: Option<[f64; 3]>,
    target: [f64; 3],
    up: [f64; 3],
    depth: f64,
    home: ViewerOut,
}

/// The frames of `cameras` (scene-file form: a `CameraJson` each, other keys such as
/// `name` ignored) with their image planes at `depth` scene units — for drawing
/// cameras that are not the session's views, such as `Session.suggestViews`'s. Throws
/// an `Error` naming the camera that is not valid, or for a depth that is not positive.
#[wasm_bindgen(js_name = framesOfCameras, unchecked_return_type = "CameraFrame[]")]
pub fn frames_of_cameras(
    #[wasm_bindgen(unchecked_param_type = "CameraJson[]")] cameras: JsValue,
    depth: f64,
) -> Result<JsValue, JsError> {
    if !(depth.is_finite() && depth > 0.0) {
        return Err(JsError::new(&format!(
            "framesOfCameras: depth {depth} is not a positive number"
        )));
    }
    let list: Vec<CameraJson> = serde_wasm_bindgen::from_value(cameras)
        .map_err(|e| JsError::new(&format!("framesOfCameras: not a list of cameras: {e}")))?;
    let out = list
        .iter()
        .enumerate()
        .map(|(i, json)| {
            let camera = json.to_camera(&format!("camera {i}"))?;
            Ok(FrameOut::new(&camera, &CameraFrame::new(&camera), depth, None))
        })
        .collect::<crate::error::Result<Vec<_>>>()?;
    to_js(&out)
}

/// The mesh for display: itself up to `max` triangles, otherwise a vertex-clustered
/// copy on the finest grid (halving from 512 cells a side) that has at most `max`.
pub fn display_mesh(mesh: &Mesh, max: usize) -> Mesh {
    if mesh.triangle_count() <= max {
        return mesh.clone();
    }
    let mut cells = 512;
    loop {
        let m = mesh.clustered(cells);
        if m.triangle_count() <= max || cells <= 4 {
            return m;
        }
        cells /= 2;
    }
}

/// A view's picture, box-filtered down by a whole factor to at most `max_side` a side:
/// its photograph, or its mask (object white, background dark grey, ignored pixels
/// mid grey) when it has none. Returns the kind, the size and RGBA8.
pub fn view_picture(view: &View, max_side: u32) -> (&'static str, u32, u32, Vec<u8>) {
    let cam = view.camera();
    let (w, h) = (cam.width, cam.height);
    let (kind, full): (&str, Vec<u8>) = match view.image() {
        Some(img) => ("image", img.data.clone()),
        None => {
            let mask = view.mask();
            let mut rgba = Vec::with_capacity(mask.data.len() * 4);
            for (i, &m) in mask.data.iter().enumerate() {
                let g = if m != 0 {
                    255
                } else if view.is_known(i) {
                    40
                } else {
                    110
                };
                rgba.extend_from_slice(&[g, g, g, 255]);
            }
            ("mask", rgba)
        }
    };
    let f = w.max(h).div_ceil(max_side.max(1)).max(1);
    if f == 1 {
        return (kind, w, h, full);
    }
    let (ow, oh) = (w.div_ceil(f), h.div_ceil(f));
    let mut out = vec![0u8; (ow * oh * 4) as usize];
    for oy in 0..oh {
        for ox in 0..ow {
            let mut sum = [0u32; 4];
            let mut n = 0;
            for y in oy * f..((oy + 1) * f).min(h) {
                for x in ox * f..((ox + 1) * f).min(w) {
                    let i = ((y * w + x) * 4) as usize;
                    for (s, v) in sum.iter_mut().zip(&full[i..i + 4]) {
                        *s += *v as u32;
                    }
                    n += 1;
                }
            }
            let o = ((oy * ow + ox) * 4) as usize;
            for (k, s) in sum.iter().enumerate() {
                out[o + k] = ((s + n / 2) / n) as u8;
            }
        }
    }
    (kind, ow, oh, out)
}

fn set(obj: &js_sys::Object, key: &str, value: &JsValue) -> Result<(), JsError> {
    js_sys::Reflect::set(obj, &JsValue::from_str(key), value)
        .map(|_| ())
        .map_err(|_| JsError::new("internal error: cannot build a JavaScript object"))
}

#[wasm_bindgen]
impl Session {
    /// The mesh for the 3D view, in the model frame: `positions` (xyz per vertex, f32)
    /// and `indices` (three per triangle). Meshes over 200,000 triangles are given as a
    /// vertex-clustered copy of at most that many (`decimated: true`); the fit itself
    /// always uses the whole mesh.
    #[wasm_bindgen(unchecked_return_type = "DisplayGeometry")]
    pub fn geometry(&self) -> Result<JsValue, JsError> {
        let source = self.estimator().mesh();
        let mesh = display_mesh(source, MAX_DISPLAY_TRIANGLES);
        let positions: Vec<f32> = mesh
            .positions
            .iter()
            .flat_map(|p| [p.x as f32, p.y as f32, p.z as f32])
            .collect();
        let indices: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
        let obj = js_sys::Object::new();
        set(&obj, "positions", &js_sys::Float32Array::from(&positions[..]).into())?;
        set(&obj, "indices", &js_sys::Uint32Array::from(&indices[..]).into())?;
        set(&obj, "triangles", &JsValue::from(mesh.triangle_count() as u32))?;
        set(&obj, "source_triangles", &JsValue::from(source.triangle_count() as u32))?;
        set(
            &obj,
            "decimated",
            &JsValue::from(mesh.triangle_count() != source.triangle_count()),
        )?;
        Ok(obj.into())
    }

    /// Each view's camera in scene-file form (SPEC §3, OpenCV axes): `{name, width,
    /// height, fx, fy, cx, cy, world_to_camera}`, `world_to_camera` 4×4 row-major.
    #[wasm_bindgen(unchecked_return_type = "SceneCamera[]")]
    pub fn cameras(&self) -> Result<JsValue, JsError> {
        let cams: Vec<SceneCamera> = self
            .estimator()
            .views()
            .iter()
            .map(|v| SceneCamera::new(v.name(), v.camera()))
            .collect();
        to_js(&cams)
    }

    /// The views' camera frames, where they look and where the 3D viewer starts
    /// (`crate::app::scene_view`), for a viewer of width/height `aspect` (1 when
    /// omitted); the image planes at 30 % of the cameras' median distance to the target.
    #[wasm_bindgen(js_name = cameraFrames, unchecked_return_type = "SceneFrames")]
    pub fn camera_frames(&self, aspect: Option<f64>) -> Result<JsValue, JsError> {
        let est = self.estimator();
        let cameras: Vec<Camera> = est.views().iter().map(|v| *v.camera()).collect();
        let s = SceneFrames::new(&cameras, bounding_radius(est.mesh()), aspect.unwrap_or(1.0));
        let frames = cameras
            .iter()
            .zip(&s.frames)
            .enumerate()
            .map(|(i, (c, f))| FrameOut::new(c, f, s.depth, Some(s.look_target(i))))
            .collect();
        to_js(&SceneFramesOut {
            frames,
            meet: s.meet.map(|v| v.to_array()),
            target: s.target.to_array(),
            up: s.up.to_array(),
            depth: s.depth,
            home: ViewerOut {
                position: s.home.position.to_array(),
                near: s.home.near,
                far: s.home.far,
                fov_deg: s.home.fov_deg,
            },
        })
    }

    /// `count` ghosts of the finished fit: poses drawn from its covariance about its
    /// pose with a generator seeded by `seed` (the same ghosts for the same seed;
    /// `uncertainty::ghost_poses`), each as its object-to-world 4×4 `[R·diag(s) | t]`,
    /// 16 numbers row-major. Empty before the fit is done and when its uncertainty could
    /// not be measured. Throws an `Error` for a covariance that is not finite.
    #[wasm_bindgen(unchecked_return_type = "number[][]")]
    pub fn ghosts(&self, count: u32, seed: u32) -> Result<JsValue, JsError> {
        let est = self.estimator();
        let Some(Ok(u)) = est.uncertainty() else {
            return to_js(&Vec::<[f64; 16]>::new());
        };
        let ghosts = ghost_poses(&est.pose(), &u.covariance, count as usize, seed as u64)?;
        let out: Vec<[f64; 16]> = ghosts.iter().map(|g| g.matrix().transpose().to_cols_array()).collect();
        to_js(&out)
    }

    /// View `view`'s picture for the 3D view's image plane: its photograph, or its mask
    /// when it has none, reduced by a whole factor to at most `max_side` pixels a side
    /// (0: 512). RGBA8, row 0 at the top.
    #[wasm_bindgen(js_name = viewPicture, unchecked_return_type = "ViewPicture")]
    pub fn view_picture(&self, view: usize, max_side: u32) -> Result<JsValue, JsError> {
        let views = self.estimator().views();
        let v = views
            .get(view)
            .ok_or_else(|| JsError::new(&format!("no view {view}: the session has {} views", views.len())))?;
        let side = if max_side == 0 { DEFAULT_PICTURE_SIDE } else { max_side };
        let (kind, w, h, rgba) = view_picture(v, side);
        let obj = js_sys::Object::new();
        set(&obj, "width", &JsValue::from(w))?;
        set(&obj, "height", &JsValue::from(h))?;
        set(&obj, "kind", &JsValue::from_str(kind))?;
        set(&obj, "rgba", &js_sys::Uint8ClampedArray::from(&rgba[..]).into())?;
        Ok(obj.into())
    }
}
