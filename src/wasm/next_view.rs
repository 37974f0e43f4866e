//! `Session.suggestViews(top, viewpoints?)`: once a fit is done, the cameras from which a
//! further photograph is predicted to shrink the pose uncertainty most (64 viewpoints on
//! a sphere around the object at the views' mean distance, or with `"above"` on its
//! upper half, with view 0's intrinsics;
//! `crate::uncertainty::next_view`), best first, each in the scene file's camera form
//! with its predicted figures — the same as `localisebot suggest-view`.

use super::session::Session;
use super::to_js;
use crate::camera::CameraJson;
use crate::uncertainty::Viewpoints;
use serde::Serialize;
use wasm_bindgen::prelude::*;

/// One suggested camera.
#[derive(Serialize)]
struct Suggestion {
    /// The camera, scene-file form (OpenCV, `world_to_camera`).
    camera: CameraJson,
    /// The expected RMS ADD with a photograph from there added, scene units.
    predicted_add_rms: f64,
    /// The expected RMS ADD now, scene units.
    current_add_rms: f64,
    /// The object's outline length seen from there, pixels.
    outline_px: f64,
    /// For an ambiguous fit: 1 − IoU between the fit's and the most alike
    /// alternative's silhouettes seen from there (null otherwise).
    discrimination: Option<f64>,
}

#[wasm_bindgen(typescript_custom_section)]
const TS_SUGGESTION: &'static str = r#"
/** A camera suggested for the next photograph (best first). */
export interface Suggestion {
  /** Scene-file form: width, height, fx, fy, cx, cy, world_to_camera (4×4 rows), convention "opencv". */
  camera: { width: number; height: number; fx: number; fy: number; cx: number; cy: number;
            world_to_camera: number[][]; convention: "opencv" };
  /** Expected RMS ADD with a photograph from there added, and now (scene units). */
  predicted_add_rms: number; current_add_rms: number;
  /** The object's outline length seen from there, pixels. */
  outline_px: number;
  /** For an ambiguous fit: 1 − IoU between the fit's and the most alike alternative's
   *  silhouettes seen from there (the views that tell them apart come first); else null. */
  discrimination: number | null;
}
"#;

#[wasm_bindgen]
impl Session {
    /// The best `top` cameras for the next photograph, once the fit is done (see the
    /// module doc), from `viewpoints`: `"sphere"` (the default, also when omitted or
    /// null) or `"above"` (the upper half of the sphere, along the views' mean
    /// image-up). Throws an `Error` before the fit is done, when its uncertainty could
    /// not be measured, or for another `viewpoints`.
    #[wasm_bindgen(js_name = suggestViews, unchecked_return_type = "Suggestion[]")]
    pub fn suggest_views(&self, top: u32, viewpoints: Option<String>) -> Result<JsValue, JsError> {
        let shell = match viewpoints.as_deref() {
            None | Some("sphere") => Viewpoints::Sphere,
            Some("above") => Viewpoints::Above,
            Some(other) => {
                return Err(JsError::new(&format!(
                    "suggestViews: viewpoints must be \"sphere\" or \"above\", got {other:?}"
                )))
            }
        };
        let ranked = self.estimator().suggest_views(None, shell)?;
        let out: Vec<Suggestion> = ranked
            .iter()
            .filter(|r| r.predicted_add_rms.is_finite())
            .take(top.max(1) as usize)
            .map(|r| Suggestion {
                camera: CameraJson::from_camera(&r.camera),
                predicted_add_rms: r.predicted_add_rms,
                current_add_rms: r.current_add_rms,
                outline_px: r.outline_px,
                discrimination: r.discrimination,
            })
            .collect();
        to_js(&out)
    }
}
