//! The WebAssembly binding (wasm32 only): `#[wasm_bindgen]` types over the core, no
//! maths. JavaScript builds a [`Session`] from a `scene.json` and its files (a
//! [`FileSet`], matched by path, then by file name), or piece by piece with a
//! [`SessionBuilder`] (a mesh's bytes, then each view's camera, mask as PNG bytes or
//! RGBA pixels, and image). It then steps the fit (`step(n)`, `stepFor(ms)`) and
//! reads the progress (phase, iteration, loss, per-view IoU, pose), each view's
//! overlay (RGBA8 for `ImageData`, the view's size) and the result (SPEC §3).
//!
//! Every core [`Error`] reaches JavaScript as an `Error` carrying its message; nothing
//! here panics on user input (the panic hook only logs bugs to the console).

use crate::camera::CameraJson;
use crate::error::{Error, Result};
use crate::estimator::{Estimator, FitSettings, Progress};
use crate::io::mask::{decode_image, decode_mask, mask_from_rgba};
use crate::io::scene::{check_mask, scene_from_parts, Scene, SceneJson};
use crate::io::{join, load_mesh, parent_dir};
use crate::mask::Mask;
use crate::mesh::Mesh;
use crate::pose::{Pose, PoseJson};
use crate::result::PoseOut;
use crate::view::{Rgba, View};
use crate::{metrics, overlay, raster};
use serde::Serialize;
use wasm_bindgen::prelude::*;
use wasm_bindgen::Clamped;

#[wasm_bindgen(typescript_custom_section)]
const TS_TYPES: &'static str = r#"
/** A camera as written in scene.json (SPEC §3). */
export interface CameraJson {
  width: number; height: number; fx: number; fy: number; cx: number; cy: number;
  world_to_camera?: number[][]; camera_to_world?: number[][];
  convention?: "opencv" | "opengl";
}
/** A pose as written in scene.json: rotation as a 3×3 row-major matrix or a quaternion [w, x, y, z]. */
export interface PoseJson {
  rotation?: number[][] | number[]; quaternion?: number[];
  translation: number[]; scale?: number[];
}
/** A pose in every form: 3×3 row-major rotation, quaternion [w, x, y, z], intrinsic XYZ Euler degrees. */
export interface PoseOut {
  rotation: number[][]; quaternion: number[]; euler_xyz_deg: number[];
  translation: number[]; scale: number[];
}
/** Where the fit stands. */
export interface Progress {
  phase: "search" | "refine" | "done";
  /** Optimiser iterations so far, all candidates and stages. */
  iteration: number;
  /** Orientation candidates scored so far, and in all. */
  searched: number; search_total: number;
  /** Refinement stage (0-based) and the number of stages; candidate being refined. */
  stage: number; stages: number; candidate: number;
  /** Loss at the current pose (NaN during the search). */
  loss: number;
  /** Hard IoU per view at the current stage's resolution. */
  view_iou: number[];
  /** Hard IoU per view at full resolution, at `pose`. */
  iou: number[];
  termination: null | "converged" | "max_iterations" | "stalled";
  done: boolean;
  /** Seconds spent in step() so far. */
  seconds: number;
  pose: PoseOut;
}
/** One view's name and size. */
export interface ViewInfo { name: string; width: number; height: number; has_image: boolean; }
/** The result of a fit (SPEC §3). */
export interface FitResult {
  pose: PoseOut; matrix: number[][];
  views: { name: string; iou: number; hausdorff_px: number }[];
  mean_iou: number; loss_history: number[]; iterations: number;
  termination: null | "converged" | "max_iterations" | "stalled";
  seconds: number; errors?: Record<string, number>;
}
"#;

/// Logs a Rust panic (a bug) to the console with its message; runs by itself when the
/// module loads.
#[wasm_bindgen(start)]
pub fn install_panic_hook() {
    console_error_panic_hook::set_once();
}

fn to_js<T: Serialize + ?Sized>(value: &T) -> Result<JsValue, JsError> {
    value
        .serialize(&serde_wasm_bindgen::Serializer::json_compatible())
        .map_err(|e| JsError::new(&format!("internal error: cannot convert to JavaScript: {e}")))
}

/// JSON text of a JavaScript value: a string as it is, anything else through `JSON.stringify`.
fn json_text(value: &JsValue) -> std::result::Result<String, String> {
    if let Some(s) = value.as_string() {
        return Ok(s);
    }
    js_sys::JSON::stringify(value)
        .ok()
        .and_then(|s| s.as_string())
        .ok_or_else(|| "expected an object or JSON text".to_string())
}

// ---- files ------------------------------------------------------------------------

/// What a file is wanted for; breaks ties between files of the same name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FileRole {
    /// A mask: among same-named files, the one whose pixels are only black and white.
    Mask,
    /// An image: among same-named files, the one that is not black and white.
    Image,
    /// Anything else (a mesh, a buffer): same-named files are an error.
    Other,
}

/// A set of named files (paths as dropped: folder-relative, or bare names).
#[wasm_bindgen]
#[derive(Debug, Default, Clone)]
pub struct FileSet {
    files: Vec<(String, Vec<u8>)>,
}

/// A path with `\` as `/`, `.` and `..` resolved, no leading `/`.
fn normalise(path: &str) -> String {
    join("", path).trim_start_matches('/').to_string()
}

/// Whether an image's pixels are all pure black or pure white grey (a mask).
fn black_and_white(bytes: &[u8]) -> bool {
    decode_image(bytes, "", "").is_ok_and(|img| {
        img.data
            .chunks_exact(4)
            .all(|p| p[0] == p[1] && p[1] == p[2] && (p[0] == 0 || p[0] == 255))
    })
}

#[wasm_bindgen]
impl FileSet {
    /// An empty set.
    #[wasm_bindgen(constructor)]
    pub fn new() -> FileSet {
        FileSet::default()
    }

    /// Adds a file. Several files may share a path (a file chooser gives bare names,
    /// so `images/a.png` and `masks/a.png` both arrive as `a.png`); an exact duplicate
    /// (same path, same bytes) is ignored.
    pub fn add(&mut self, path: &str, bytes: Vec<u8>) {
        let path = normalise(path);
        if !self.files.iter().any(|(p, b)| *p == path && *b == bytes) {
            self.files.push((path, bytes));
        }
    }

    /// The number of files.
    #[wasm_bindgen(getter)]
    pub fn length(&self) -> usize {
        self.files.len()
    }

    /// The files' paths, normalised (`/` separators, no `./`).
    pub fn names(&self) -> Vec<String> {
        self.files.iter().map(|(p, _)| p.clone()).collect()
    }
}

impl FileSet {
    /// The file a scene asks for as `wanted`: the file of that exact path; else the
    /// one whose path ends with it, or it with the file's (`masks/a.png` is served by
    /// `scene/masks/a.png` or by a bare `a.png`, never by `images/a.png`); else the
    /// same ignoring case. Several files at the first level that matches are told
    /// apart by `role`; `Err` names them when that fails. `Ok(None)`: no such file.
    pub fn find(&self, wanted: &str, role: FileRole) -> std::result::Result<Option<&[u8]>, String> {
        Ok(self.find_entry(wanted, role)?.map(|(_, bytes)| bytes.as_slice()))
    }

    /// As [`find`](Self::find), the matching (path, bytes) entry.
    fn find_entry(&self, wanted: &str, role: FileRole) -> std::result::Result<Option<&(String, Vec<u8>)>, String> {
        let w = normalise(wanted);
        let suffix = |a: &str, b: &str| a.len() > b.len() && a.ends_with(b) && a[..a.len() - b.len()].ends_with('/');
        let (wl, lower) = (w.to_ascii_lowercase(), |f: &str| f.to_ascii_lowercase());
        let exact = |f: &str| f == w;
        let by_suffix = |f: &str| suffix(f, &w) || suffix(&w, f);
        let any_case = |f: &str| suffix(&lower(f), &wl) || suffix(&wl, &lower(f)) || lower(f) == wl;
        let levels: [&dyn Fn(&str) -> bool; 3] = [&exact, &by_suffix, &any_case];
        for matches in levels {
            let hits: Vec<&(String, Vec<u8>)> = self.files.iter().filter(|(p, _)| matches(p)).collect();
            if hits.len() == 1 {
                return Ok(Some(hits[0]));
            }
            if hits.len() > 1 {
                let keep: Vec<_> = match role {
                    FileRole::Mask => hits.iter().filter(|f| black_and_white(&f.1)).collect(),
                    FileRole::Image => hits.iter().filter(|f| !black_and_white(&f.1)).collect(),
                    FileRole::Other => vec![],
                };
                if keep.len() == 1 {
                    return Ok(Some(keep[0]));
                }
                let names: Vec<&str> = hits.iter().map(|f| f.0.as_str()).collect();
                return Err(format!(
                    "ambiguous: {} files could be it ({}); give the files in their folders \
                     (drop the folder) so that their paths tell them apart",
                    hits.len(),
                    names.join(", ")
                ));
            }
        }
        Ok(None)
    }

    /// The scene `scene_file` (JSON `text`) with the mesh, masks and images it names
    /// taken from this set (paths joined onto the scene file's folder, then
    /// [`find`](Self::find), as a mask or an image), and warnings: an image not in
    /// the set (or only as the view's mask) is left out, for images are only shown.
    pub fn load_scene(&self, scene_file: &str, text: &str) -> Result<(Scene, Vec<String>)> {
        let mut json = SceneJson::parse(text, scene_file)?;
        let dir = parent_dir(scene_file);
        let missing = |path: String| Error::MissingFile {
            file: path,
            referrer: scene_file.into(),
        };
        // Every mask and image found first, by role; `fetch` then serves them by the
        // path written in the scene (an image written as its mask's path gets "#image").
        let mut found: Vec<(String, &[u8])> = Vec::new();
        let mut warnings = Vec::new();
        for v in &mut json.views {
            let mask = self
                .find_entry(&join(dir, &v.mask), FileRole::Mask)
                .map_err(|problem| Error::Mask {
                    view: v.name.clone(),
                    file: v.mask.clone(),
                    problem,
                })?
                .ok_or_else(|| missing(join(dir, &v.mask)))?;
            found.push((v.mask.clone(), &mask.1));
            let Some(image) = v.image.take() else { continue };
            match self.find_entry(&join(dir, &image), FileRole::Image) {
                Ok(Some(entry)) if !std::ptr::eq(entry, mask) => {
                    let key = if image == v.mask {
                        format!("{image}#image")
                    } else {
                        image
                    };
                    found.push((key.clone(), &entry.1));
                    v.image = Some(key);
                }
                Ok(_) => warnings.push(format!(
                    "view '{}': image '{image}' not given: showing the mask",
                    v.name
                )),
                Err(problem) => {
                    return Err(Error::Image {
                        view: v.name.clone(),
                        file: image,
                        problem,
                    })
                }
            }
        }
        let mesh_path = join(dir, &json.mesh);
        let mesh_bytes = self
            .find(&mesh_path, FileRole::Other)
            .map_err(|problem| Error::Mesh {
                file: mesh_path.clone(),
                problem,
            })?
            .ok_or_else(|| missing(mesh_path.clone()))?;
        let mesh_dir = parent_dir(&mesh_path);
        let extra = |uri: &str| {
            self.find(&join(mesh_dir, uri), FileRole::Other)
                .ok()
                .flatten()
                .map(<[u8]>::to_vec)
        };
        let mesh = load_mesh(&mesh_path, mesh_bytes, &extra)?;
        let fetch = |rel: &str| -> Result<Vec<u8>> {
            let bytes = found.iter().find(|(p, _)| p == rel).map(|(_, b)| b.to_vec());
            bytes.ok_or_else(|| missing(join(dir, rel)))
        };
        Ok((scene_from_parts(scene_file, json, mesh, &fetch)?, warnings))
    }
}

/// Checks a mesh file; returns its triangle count. `extra` supplies a `.gltf`'s buffers.
#[wasm_bindgen(js_name = checkMesh)]
pub fn check_mesh(file_name: &str, bytes: &[u8], extra: &FileSet) -> Result<usize, JsError> {
    let dir = parent_dir(file_name);
    let resolve = |uri: &str| {
        extra
            .find(&join(dir, uri), FileRole::Other)
            .ok()
            .flatten()
            .map(<[u8]>::to_vec)
    };
    Ok(load_mesh(file_name, bytes, &resolve)?.triangles.len())
}

// ---- building a session piece by piece -----------------------------------------------

/// Builds a [`Session`] from a mesh and views given one by one; each call checks its
/// input at once and throws an `Error` naming the view and the problem.
#[wasm_bindgen]
#[derive(Default)]
pub struct SessionBuilder {
    mesh: Option<Mesh>,
    views: Vec<View>,
    initial_pose: Option<Pose>,
    ground_truth: Option<Pose>,
}

fn parse_camera(view: &str, camera: &JsValue) -> Result<crate::camera::Camera> {
    let bad = |problem: String| Error::Camera {
        view: view.into(),
        problem,
    };
    let text = json_text(camera).map_err(bad)?;
    let json: CameraJson = serde_json::from_str(&text).map_err(|e| bad(format!("not a valid camera: {e}")))?;
    json.to_camera(view)
}

fn parse_pose(what: &str, pose: &JsValue) -> Result<Pose> {
    let text = json_text(pose).map_err(|e| Error::Pose(format!("{what}: {e}")))?;
    let json: PoseJson =
        serde_json::from_str(&text).map_err(|e| Error::Pose(format!("{what}: not a valid pose: {e}")))?;
    json.to_pose().map_err(|e| Error::Pose(format!("{what}: {e}")))
}

fn rgba(view: &str, what: &str, width: u32, height: u32, data: Vec<u8>) -> Result<Rgba> {
    if data.len() as u64 != 4 * width as u64 * height as u64 {
        let problem = format!(
            "has {} bytes, but {width}×{height} RGBA pixels need {}",
            data.len(),
            4 * width * height
        );
        return Err(match what {
            "mask" => Error::Mask {
                view: view.into(),
                file: "RGBA pixels".into(),
                problem,
            },
            _ => Error::Image {
                view: view.into(),
                file: "RGBA pixels".into(),
                problem,
            },
        });
    }
    Ok(Rgba { width, height, data })
}

#[wasm_bindgen]
impl SessionBuilder {
    /// An empty builder.
    #[wasm_bindgen(constructor)]
    pub fn new() -> SessionBuilder {
        SessionBuilder::default()
    }

    /// Sets the mesh from its file's bytes (`.glb`, `.gltf`, `.obj`); `extra` holds
    /// the files a `.gltf` refers to (its `.bin` buffers), by name.
    pub fn mesh(&mut self, file_name: &str, bytes: &[u8], extra: Option<FileSet>) -> Result<(), JsError> {
        let extra = extra.unwrap_or_default();
        let dir = parent_dir(file_name);
        let resolve = |uri: &str| {
            extra
                .find(&join(dir, uri), FileRole::Other)
                .ok()
                .flatten()
                .map(<[u8]>::to_vec)
        };
        self.mesh = Some(load_mesh(file_name, bytes, &resolve)?);
        Ok(())
    }

    /// Adds a view: its camera (an object or JSON text, as in `scene.json`), its mask
    /// as PNG bytes and optionally its image as PNG bytes (for display).
    #[wasm_bindgen(js_name = addView)]
    pub fn add_view(
        &mut self,
        name: &str,
        #[wasm_bindgen(unchecked_param_type = "CameraJson | string")] camera: JsValue,
        mask_png: &[u8],
        image_png: Option<Vec<u8>>,
    ) -> Result<(), JsError> {
        let camera = parse_camera(name, &camera)?;
        let mask = decode_mask(mask_png, name, "mask PNG")?;
        let image = image_png.map(|b| decode_image(&b, name, "image PNG")).transpose()?;
        self.push_view(name, camera, mask, image)?;
        Ok(())
    }

    /// Adds a view whose mask (and image) are RGBA8 pixels, `width` × `height`, row 0
    /// at the top (e.g. `ImageData.data`); the mask follows the PNG rule (alpha if not
    /// opaque everywhere, else luma).
    #[wasm_bindgen(js_name = addViewRgba)]
    pub fn add_view_rgba(
        &mut self,
        name: &str,
        #[wasm_bindgen(unchecked_param_type = "CameraJson | string")] camera: JsValue,
        width: u32,
        height: u32,
        mask_rgba: Vec<u8>,
        image_rgba: Option<Vec<u8>>,
    ) -> Result<(), JsError> {
        let camera = parse_camera(name, &camera)?;
        let mask = mask_from_rgba(&rgba(name, "mask", width, height, mask_rgba)?);
        let image = image_rgba.map(|d| rgba(name, "image", width, height, d)).transpose()?;
        self.push_view(name, camera, mask, image)?;
        Ok(())
    }

    /// Sets a starting pose (skips the orientation search): an object or JSON text.
    #[wasm_bindgen(js_name = initialPose)]
    pub fn initial_pose(
        &mut self,
        #[wasm_bindgen(unchecked_param_type = "PoseJson | string")] pose: JsValue,
    ) -> Result<(), JsError> {
        self.initial_pose = Some(parse_pose("initial pose", &pose)?);
        Ok(())
    }

    /// Sets the true pose, for the result's error figures: an object or JSON text.
    #[wasm_bindgen(js_name = groundTruth)]
    pub fn ground_truth(
        &mut self,
        #[wasm_bindgen(unchecked_param_type = "PoseJson | string")] pose: JsValue,
    ) -> Result<(), JsError> {
        self.ground_truth = Some(parse_pose("ground truth pose", &pose)?);
        Ok(())
    }

    /// The session (consumes the builder).
    pub fn build(self) -> Result<Session, JsError> {
        let mesh = self
            .mesh
            .ok_or_else(|| Error::Settings("no mesh: call mesh() before build()".into()))?;
        Ok(Session::new(mesh, self.views, self.initial_pose, self.ground_truth)?)
    }
}

impl SessionBuilder {
    fn push_view(&mut self, name: &str, camera: crate::camera::Camera, mask: Mask, image: Option<Rgba>) -> Result<()> {
        if self.views.iter().any(|v| v.name == name) {
            return Err(Error::Settings(format!("two views are named '{name}'")));
        }
        check_mask(name, "mask", &mask, camera.width, camera.height)?;
        if let Some(img) = &image {
            if (img.width, img.height) != (camera.width, camera.height) {
                return Err(Error::Image {
                    view: name.into(),
                    file: "image".into(),
                    problem: format!(
                        "is {}×{} but the camera is {}×{}",
                        img.width, img.height, camera.width, camera.height
                    ),
                });
            }
        }
        self.views.push(View {
            name: name.into(),
            camera,
            mask,
            image,
        });
        Ok(())
    }
}

// ---- the session ------------------------------------------------------------------

/// A fit in progress: the estimator, the time spent stepping it, the loss of every
/// refinement iteration, and the silhouettes rendered at the current pose (cached
/// until the next step).
#[wasm_bindgen]
pub struct Session {
    est: Estimator,
    initial_pose: Option<Pose>,
    ground_truth: Option<Pose>,
    seconds: f64,
    losses: Vec<f64>,
    iteration: usize,
    rendered: Option<Vec<Mask>>,
    warnings: Vec<String>,
}

/// Progress as JavaScript sees it: the core's, plus the pose and full-resolution IoUs.
#[derive(Serialize)]
struct ProgressOut<'a> {
    #[serde(flatten)]
    core: &'a Progress,
    pose: PoseOut,
    stages: usize,
    done: bool,
    seconds: f64,
    iou: Vec<f64>,
}

#[derive(Serialize)]
struct ViewInfo<'a> {
    name: &'a str,
    width: u32,
    height: u32,
    has_image: bool,
}

impl Session {
    /// A session over a loaded mesh and views.
    pub fn new(
        mesh: Mesh,
        views: Vec<View>,
        initial_pose: Option<Pose>,
        ground_truth: Option<Pose>,
    ) -> Result<Session> {
        let est = Estimator::new(mesh, views, initial_pose, FitSettings::default())?;
        Ok(Session {
            est,
            initial_pose,
            ground_truth,
            seconds: 0.0,
            losses: Vec::new(),
            iteration: 0,
            rendered: None,
            warnings: Vec::new(),
        })
    }

    /// The estimator.
    pub fn estimator(&self) -> &Estimator {
        &self.est
    }

    /// One step, recording the loss when an optimiser iteration was done.
    fn step_once(&mut self) -> Progress {
        let p = self.est.step();
        if p.iteration > self.iteration {
            self.iteration = p.iteration;
            self.losses.push(p.loss);
        }
        self.rendered = None;
        p
    }

    /// The full-resolution silhouettes at the current pose (rendered once per step).
    fn rendered(&mut self) -> &[Mask] {
        let est = &self.est;
        self.rendered.get_or_insert_with(|| {
            let pose = est.pose();
            est.views()
                .iter()
                .map(|v| raster::hard::render(est.mesh(), &pose, &v.camera))
                .collect()
        })
    }

    /// Full-resolution hard IoU per view at the current pose.
    pub fn full_ious(&mut self) -> Vec<f64> {
        let rendered = self.rendered().to_vec();
        self.est
            .views()
            .iter()
            .zip(&rendered)
            .map(|(v, m)| metrics::hard_iou(m, &v.mask))
            .collect()
    }

    fn progress_out(&mut self, p: &Progress) -> Result<JsValue, JsError> {
        let iou = self.full_ious();
        to_js(&ProgressOut {
            core: p,
            pose: PoseOut::from_pose(&p.pose),
            stages: self.est.settings().stages.len(),
            done: self.est.is_done(),
            seconds: self.seconds,
            iou,
        })
    }
}

#[wasm_bindgen]
impl Session {
    /// A session from a scene file's text and the files it names (mesh, masks, images),
    /// matched by path relative to the scene file, then by file name.
    #[wasm_bindgen(js_name = fromScene)]
    pub fn from_scene(scene_file: &str, scene_text: &str, files: &FileSet) -> Result<Session, JsError> {
        let (scene, warnings) = files.load_scene(scene_file, scene_text)?;
        let mut session = Session::new(scene.mesh, scene.views, scene.initial_pose, scene.ground_truth_pose)?;
        session.warnings = warnings;
        Ok(session)
    }

    /// The number of views.
    #[wasm_bindgen(getter, js_name = viewCount)]
    pub fn view_count(&self) -> usize {
        self.est.views().len()
    }

    /// Each view's name and size.
    #[wasm_bindgen(unchecked_return_type = "ViewInfo[]")]
    pub fn views(&self) -> Result<JsValue, JsError> {
        let info: Vec<ViewInfo> = self
            .est
            .views()
            .iter()
            .map(|v| ViewInfo {
                name: &v.name,
                width: v.camera.width,
                height: v.camera.height,
                has_image: v.image.is_some(),
            })
            .collect();
        to_js(&info)
    }

    /// Does `n` units of work (each a batch of search candidates or one optimiser
    /// iteration; fewer once the fit is done) and reports where the fit stands.
    #[wasm_bindgen(unchecked_return_type = "Progress")]
    pub fn step(&mut self, n: u32) -> Result<JsValue, JsError> {
        let t0 = js_sys::Date::now();
        let mut p = None;
        for _ in 0..n {
            if self.est.is_done() {
                break;
            }
            p = Some(self.step_once());
        }
        self.seconds += (js_sys::Date::now() - t0) / 1000.0;
        let p = p.unwrap_or_else(|| self.est.progress());
        self.progress_out(&p)
    }

    /// Steps until `budget_ms` milliseconds have passed (at least one step) or the fit
    /// is done; reports where the fit stands.
    #[wasm_bindgen(js_name = stepFor, unchecked_return_type = "Progress")]
    pub fn step_for(&mut self, budget_ms: f64) -> Result<JsValue, JsError> {
        let t0 = js_sys::Date::now();
        let mut p = None;
        while !self.est.is_done() {
            p = Some(self.step_once());
            if js_sys::Date::now() - t0 >= budget_ms {
                break;
            }
        }
        self.seconds += (js_sys::Date::now() - t0) / 1000.0;
        let p = p.unwrap_or_else(|| self.est.progress());
        self.progress_out(&p)
    }

    /// Where the fit stands, without stepping.
    #[wasm_bindgen(unchecked_return_type = "Progress")]
    pub fn progress(&mut self) -> Result<JsValue, JsError> {
        let p = self.est.progress();
        self.progress_out(&p)
    }

    /// What was left out when the session was made (images not given).
    pub fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }

    /// Whether the fit has finished.
    #[wasm_bindgen(getter)]
    pub fn done(&self) -> bool {
        self.est.is_done()
    }

    /// Seconds spent stepping so far.
    #[wasm_bindgen(getter)]
    pub fn seconds(&self) -> f64 {
        self.seconds
    }

    /// The current pose (the best so far once done).
    #[wasm_bindgen(unchecked_return_type = "PoseOut")]
    pub fn pose(&self) -> Result<JsValue, JsError> {
        to_js(&PoseOut::from_pose(&self.est.pose()))
    }

    /// The loss of every refinement iteration so far, all candidates, in order.
    pub fn losses(&self) -> Vec<f64> {
        self.losses.clone()
    }

    /// Full-resolution hard IoU per view at the current pose.
    #[wasm_bindgen(js_name = viewIou)]
    pub fn view_iou(&mut self) -> Vec<f64> {
        self.full_ious()
    }

    /// View `view`'s overlay at the current pose: its image (or mask), the mask's
    /// outline and the rendered contour, RGBA8, the view's width × height, for `ImageData`.
    pub fn overlay(&mut self, view: usize) -> Result<Clamped<Vec<u8>>, JsError> {
        let n = self.est.views().len();
        if view >= n {
            return Err(JsError::new(&format!("no view {view}: the session has {n} views")));
        }
        let rendered = self.rendered()[view].clone();
        Ok(Clamped(overlay::overlay(&self.est.views()[view], Some(&rendered)).data))
    }

    /// The result (SPEC §3) at the current pose, as an object.
    #[wasm_bindgen(unchecked_return_type = "FitResult")]
    pub fn result(&self) -> Result<JsValue, JsError> {
        to_js(&self.est.result(self.seconds, self.ground_truth.as_ref()))
    }

    /// The result (SPEC §3) at the current pose, as pretty JSON text.
    #[wasm_bindgen(js_name = resultJson)]
    pub fn result_json(&self) -> Result<String, JsError> {
        let r = self.est.result(self.seconds, self.ground_truth.as_ref());
        serde_json::to_string_pretty(&r).map_err(|e| JsError::new(&format!("internal error: {e}")))
    }

    /// Starts the fit again from the beginning (same inputs, time and losses cleared).
    pub fn reset(&mut self) -> Result<(), JsError> {
        let est = Estimator::new(
            self.est.mesh().clone(),
            self.est.views().to_vec(),
            self.initial_pose,
            self.est.settings().clone(),
        )?;
        self.est = est;
        self.seconds = 0.0;
        self.losses.clear();
        self.iteration = 0;
        self.rendered = None;
        Ok(())
    }
}
