//! [`SessionBuilder`]: a session from a mesh's bytes and views given one by one
//! (camera as an object or JSON text; mask and image as PNG bytes or RGBA pixels),
//! each checked as it arrives.

use super::{json_text, FileSet, Session};
use crate::camera::{Camera, CameraJson};
use crate::error::{Error, Result};
use crate::io::mask::{decode_image_sized, decode_mask_sized, mask_from_rgba};
use crate::limits::Limits;
use crate::mask::Mask;
use crate::mesh::Mesh;
use crate::pose::{Pose, PoseJson};
use crate::view::{Rgba, View, ViewSources};
use wasm_bindgen::prelude::*;

/// Builds a [`Session`] from a mesh and views given one by one; each call checks its
/// input at once and throws an `Error` naming the view and the problem.
#[wasm_bindgen]
#[derive(Default)]
pub struct SessionBuilder {
    limits: Limits,
    mesh: Option<Mesh>,
    views: Vec<View>,
    initial_pose: Option<Pose>,
    ground_truth: Option<Pose>,
}

fn parse_camera(view: &str, camera: &JsValue) -> Result<Camera> {
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
    // u64: `width` and `height` come from JavaScript and may be anything.
    let need = 4 * width as u64 * height as u64;
    if data.len() as u64 != need {
        let problem = format!("has {} bytes, but {width}×{height} RGBA pixels need {need}", data.len());
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
        let mut extra = extra.unwrap_or_default();
        extra.set_limits(self.limits);
        self.mesh = Some(extra.load_mesh(file_name, bytes)?);
        Ok(())
    }

    /// Sets an input limit of the later calls (as `FileSet.setLimit`).
    #[wasm_bindgen(js_name = setLimit)]
    pub fn set_limit(&mut self, name: &str, value: f64) -> Result<(), JsError> {
        self.limits.set(name, super::files::whole(name, value)?)?;
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
        self.check_pixels(name, &camera)?;
        let (w, h) = (camera.width, camera.height);
        let mask = decode_mask_sized(mask_png, name, "mask PNG", w, h)?;
        let image = image_png
            .map(|b| decode_image_sized(&b, name, "image PNG", w, h))
            .transpose()?;
        self.push_view(
            name,
            camera,
            mask,
            image,
            ViewSources::files("mask PNG", "", "image PNG"),
        )?;
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
        self.check_pixels(name, &camera)?;
        let mask = mask_from_rgba(&rgba(name, "mask", width, height, mask_rgba)?);
        let image = image_rgba.map(|d| rgba(name, "image", width, height, d)).transpose()?;
        self.push_view(
            name,
            camera,
            mask,
            image,
            ViewSources::files("RGBA pixels", "", "RGBA pixels"),
        )?;
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
    /// The view count and pixels with `camera`'s, against the limits, before its
    /// mask or image is decoded.
    fn check_pixels(&self, name: &str, camera: &Camera) -> Result<()> {
        self.limits.check_views(name, self.views.len() as u64 + 1)?;
        let total: u64 = self
            .views
            .iter()
            .map(|v| v.camera().width as u64 * v.camera().height as u64)
            .sum::<u64>()
            + camera.width as u64 * camera.height as u64;
        self.limits.check_pixels(name, camera.width, camera.height, total)
    }

    fn push_view(
        &mut self,
        name: &str,
        camera: Camera,
        mask: Mask,
        image: Option<Rgba>,
        sources: ViewSources,
    ) -> Result<()> {
        if self.views.iter().any(|v| v.name() == name) {
            return Err(Error::Settings(format!("two views are named '{name}'")));
        }
        self.views.push(View::new(name, camera, mask, None, image, &sources)?);
        Ok(())
    }
}
