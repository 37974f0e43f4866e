//! The WebAssembly binding (wasm32 only): `#[wasm_bindgen]` types over the core, no
//! maths. JavaScript builds a [`Session`] from whatever files were dropped (a
//! [`FileSet`]; `Session.fromFiles` decides which is the scene, the mesh, each view's
//! mask and image, by the policy of `io::fileset`), from a `scene.json` and its files,
//! or piece by piece with a
//! [`SessionBuilder`] (a mesh's bytes, then each view's camera, mask as PNG bytes or
//! RGBA pixels, and image). It then steps the fit (`step(n)`, `stepFor(ms)`) and
//! reads the progress (phase, iteration, loss, per-view IoU, pose), each view's
//! overlay (RGBA8 for `ImageData`, the view's size) and the result (SPEC §3).
//!
//! Every core [`Error`](crate::Error) reaches JavaScript as an `Error` carrying its message; nothing
//! here panics on user input (the panic hook only logs bugs to the console).
//!
//! - `files`: [`FileSet`] (a wrapper of `io::fileset::FileSet`), `checkMesh`,
//!   `sceneFiles` and `meshFiles` (what a scene or a glTF names);
//! - `builder`: [`SessionBuilder`], a session from parts;
//! - `session`: [`Session`], the fit as JavaScript drives it (here, or with a pool:
//!   `request`, `splitRequest`, `respond`);
//! - `shard`: [`WorkerShard`] (`Shard` in JavaScript), a pool Worker's share of a
//!   session's work, built once from the session's files;
//! - `scene_view`: what the page's 3D view draws, a second `impl Session` block
//!   (`geometry`, `cameras`, `viewPicture`, `cameraFrames`, `ghosts`), and
//!   `framesOfCameras`;
//! - `next_view`: `Session.suggestViews`, the cameras for the next photograph;
//! - `photo`: [`PhotoSession`], photographs and boxes in: the segmentation rounds, each
//!   round's fit a `Session`;
//! - `cameras`: `Session.setRefineCameras`, the camera-correction switch.

mod builder;
mod cameras;
mod files;
mod next_view;
mod photo;
mod scene_view;
mod session;
mod shard;

pub use builder::SessionBuilder;
pub use files::{check_mesh, mesh_files, scene_files, FileRole, FileSet, Plan};
pub use photo::PhotoSession;
pub use scene_view::{display_mesh, frames_of_cameras, MAX_DISPLAY_TRIANGLES};
pub use session::Session;
pub use shard::WorkerShard;

use serde::Serialize;
use wasm_bindgen::prelude::*;

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
  termination: null | "converged" | "completed" | "stalled";
  /** The verdict once the fit is done: "ok", "poor", "ambiguous" (another pose explains the masks
   *  nearly as well: FitResult.alternatives) or "failed" (a failed fit is never "converged"). */
  verdict: null | "ok" | "poor" | "ambiguous" | "failed";
  /** Why the verdict is not "ok", one line each; the views it doubts. */
  verdict_reasons: string[]; doubted_views: string[];
  done: boolean;
  /** Seconds spent in step() so far. */
  seconds: number;
  pose: PoseOut;
  /** The pose's object-to-world 4×4 `[R·diag(s) | t]`, rows (as FitResult's `matrix`). */
  matrix: number[][];
}
/** One view's name and size. */
export interface ViewInfo { name: string; width: number; height: number; has_image: boolean; }
/** One view's camera correction, in its camera's frame. */
export interface CameraCorrection {
  view: string;
  /** Rotation vector, degrees; translation, scene units. */
  rotation_deg: number[]; translation: number[];
  /** Its angle (degrees) and its shift as a % of the camera's distance to the object. */
  angle_deg: number; shift_pct: number;
  /** The corrected world-to-camera 4×4, rows. */
  world_to_camera: number[][];
}
/** Readable standard deviations of the pose covariance. */
export interface StdDev {
  /** About each model axis, degrees. */
  rotation_deg: number[];
  /** Translation, scene units (world axes). */
  translation: number[];
  /** Scale along each model axis, % of the scale. */
  scale_pct: number[];
  /** The ADD (mean model-point displacement) expected from the covariance, and the ADD within which the
   *  truth lies with 95 % confidence (for an ambiguous fit, reaching its alternatives too), scene units. */
  add_mean: number; add_95: number;
  /** The 95th percentile from this pose's covariance alone. */
  add_95_alone: number;
  /** The object's diameter at the pose, scene units. */
  diameter: number;
  /** RMS distance between the model's outline and the masks' contours at the optimum, canvas pixels. */
  boundary_rms_px: number;
}
/** A pose that competes with the fit's (FitResult.alternatives). */
export interface Alternative {
  pose: PoseOut; matrix: number[][];
  /** Per-view hard IoU at full resolution, and their mean; its loss at the last stage. */
  view_iou: number[]; mean_iou: number; loss: number;
  /** The rotation (degrees) and the ADD over the diameter from the fit's pose, up to the object's symmetries. */
  rotation_deg: number; add_rel: number;
  /** Its own covariance and standard deviations. */
  covariance: number[][] | null; std_dev: StdDev | null;
}
/** A view of a PhotoSession: its name and size, and whether the scene gave its mask. */
export interface PhotoViewInfo { name: string; width: number; height: number; has_mask: boolean; }
/** A view's box in a PhotoSession, image pixels [x_min, y_min, x_max, y_max]: drawn (or in the scene),
 *  or proposed by the other views' geometry; and the points clicked, [x, y, 1 on the object | 0 off it]. */
export interface ViewBox {
  view: string; has_mask: boolean;
  given: number[] | null; proposed: number[] | null; points: number[][];
}
/** How a mask made from a photograph came about (FitResult.masks). */
export interface MaskReport {
  view: string; first_box_from: "box" | "geometry"; first_box: number[];
  /** Each round's object pixels, and its IoU with the round before. */
  areas: number[]; changes: number[];
  /** Which of the segmenter's readings each round took. */
  picks: number[];
  score: number;
  /** IoU of the segmenter's final mask with the final pose's silhouette. */
  iou_with_fit: number;
  /** The returned mask: the final pose's silhouette where the segmenter saw the
   * object ("fit"), or the segmenter's own ("segmenter", when they disagree). */
  returned: "fit" | "segmenter";
}
/** The result of a fit (SPEC §3). */
export interface FitResult {
  pose: PoseOut; matrix: number[][];
  views: { name: string; iou: number; hausdorff_px: number }[];
  mean_iou: number; loss_history: number[]; iterations: number;
  termination: null | "converged" | "completed" | "stalled";
  /** "ok", "poor", "ambiguous" or "failed", with the reasons and the views it doubts. */
  verdict: null | "ok" | "poor" | "ambiguous" | "failed"; verdict_reasons: string[]; doubted_views: string[];
  /** For an ambiguous fit, the other poses that explain the masks nearly as well, best first. */
  alternatives?: Alternative[];
  /** The pose covariance once done: 9×9 rows in [ω (rad; right tangent, R_true ≈ R·exp([ω]×)), t (scene units), log s]. */
  covariance: number[][] | null;
  /** Its readable standard deviations once done. */
  std_dev: StdDev | null;
  /** Why the uncertainty could not be measured, when it could not. */
  uncertainty_error?: string;
  /** Each view's camera correction (camera frame), with setRefineCameras(true). */
  camera_corrections?: CameraCorrection[];
  /** Why the cameras could not be corrected, when they could not. */
  camera_correction_error?: string;
  /** The fraction of the loss the corrections removed; they are applied (pose, figures, uncertainty) only when it reaches min_reduction. */
  camera_test?: { loss_reduction: number; min_reduction: number; applied: boolean };
  seconds: number;
  /** The masks made from photographs (a PhotoSession's result). */
  masks?: MaskReport[];
  /** Against the ground truth (its symmetric equivalent closest to the estimate), when given. */
  errors?: Record<string, number>; symmetric?: boolean;
}
"#;

/// Logs a Rust panic (a bug) to the console with its message; runs by itself when the
/// module loads.
#[wasm_bindgen(start)]
pub fn install_panic_hook() {
    console_error_panic_hook::set_once();
}

pub(crate) fn to_js<T: Serialize + ?Sized>(value: &T) -> Result<JsValue, JsError> {
    value
        .serialize(&serde_wasm_bindgen::Serializer::json_compatible())
        .map_err(|e| JsError::new(&format!("internal error: cannot convert to JavaScript: {e}")))
}

/// JSON text of a JavaScript value: a string as it is, anything else through `JSON.stringify`.
pub(crate) fn json_text(value: &JsValue) -> std::result::Result<String, String> {
    if let Some(s) = value.as_string() {
        return Ok(s);
    }
    js_sys::JSON::stringify(value)
        .ok()
        .and_then(|s| s.as_string())
        .ok_or_else(|| "expected an object or JSON text".to_string())
}
