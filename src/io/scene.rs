//! The scene file (`scene.json`, SPEC §3): its wire form [`SceneJson`], and
//! [`load_scene`], which resolves the mesh, masks and images it names into a
//! validated [`Scene`].

use crate::camera::CameraJson;
use crate::error::{Error, Result};
use crate::io::mask::{decode_image_sized, decode_mask_sized};
use crate::io::{join, load_mesh, parent_dir, Resolver};
use crate::mesh::Mesh;
use crate::pose::{Pose, PoseJson};
use crate::view::{View, ViewSources};
use serde::{Deserialize, Serialize};

/// One view's entry in the scene file.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct ViewJson {
    /// Unique name.
    pub name: String,
    /// Optional photograph, relative to the scene file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub image: Option<String>,
    /// Mask PNG, relative to the scene file.
    pub mask: String,
    /// Optional ignore mask PNG (unknown pixels: occluders, other objects), relative
    /// to the scene file; same size and pixel rule as the mask.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ignore: Option<String>,
    /// Camera intrinsics and extrinsics.
    pub camera: CameraJson,
}

/// The scene file's wire form.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct SceneJson {
    /// Format version (1).
    #[serde(default = "one")]
    pub version: u32,
    /// The mesh file, relative to the scene file.
    pub mesh: String,
    /// The views.
    pub views: Vec<ViewJson>,
    /// A starting pose that skips the orientation search.
    #[serde(default)]
    pub initial_pose: Option<PoseJson>,
    /// The true pose, for evaluation.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ground_truth_pose: Option<PoseJson>,
    /// Grasps in the object frame (see ARCHITECTURE.md).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub grasps: Vec<serde_json::Value>,
}

fn one() -> u32 {
    1
}

/// A loaded, validated scene.
#[derive(Debug, Clone)]
pub struct Scene {
    /// The object's mesh, model frame.
    pub mesh: Mesh,
    /// The views, in file order.
    pub views: Vec<View>,
    /// A given starting pose.
    pub initial_pose: Option<Pose>,
    /// A given true pose.
    pub ground_truth_pose: Option<Pose>,
    /// Grasps in the object frame, validated.
    pub grasps: Vec<crate::io::grasp::Grasp>,
    /// The file as read.
    pub json: SceneJson,
    /// What was accepted with a reservation (e.g. a camera rotation projected onto
    /// SO(3)), one line each, naming the view.
    pub warnings: Vec<String>,
}

impl SceneJson {
    /// Parses scene JSON text; `file` names it in errors.
    pub fn parse(text: &str, file: &str) -> Result<SceneJson> {
        let s: SceneJson = serde_json::from_str(text).map_err(|e| Error::Json {
            file: file.into(),
            problem: e.to_string(),
        })?;
        if s.version != 1 {
            return Err(Error::Json {
                file: file.into(),
                problem: format!("unsupported scene version {} (expected 1)", s.version),
            });
        }
        Ok(s)
    }

    /// Pretty JSON text.
    pub fn to_json_string(&self) -> String {
        serde_json::to_string_pretty(self).expect("scene serialisation cannot fail")
    }
}

/// Loads a scene: parses `text` (the file `scene_file`), fetches every file it names
/// through `files` (paths joined onto the scene file's folder) and validates it all.
pub fn load_scene(scene_file: &str, text: &str, files: Resolver) -> Result<Scene> {
    let json = SceneJson::parse(text, scene_file)?;
    let dir = parent_dir(scene_file);
    let fetch = |rel: &str, referrer: &str| -> Result<Vec<u8>> {
        files(&join(dir, rel)).ok_or_else(|| Error::MissingFile {
            file: join(dir, rel),
            referrer: referrer.into(),
        })
    };
    let mesh_bytes = fetch(&json.mesh, scene_file)?;
    let mesh_path = join(dir, &json.mesh);
    let mesh_dir = parent_dir(&mesh_path).to_string();
    let mesh = load_mesh(&mesh_path, &mesh_bytes, &|uri| files(&join(&mesh_dir, uri)))?;
    scene_from_parts(scene_file, json, mesh, &|rel| fetch(rel, scene_file))
}

/// Builds a scene from its parsed JSON and an already loaded mesh; `fetch` supplies
/// each mask and image by the path written in the scene.
pub fn scene_from_parts(
    scene_file: &str,
    json: SceneJson,
    mesh: Mesh,
    fetch: &dyn Fn(&str) -> Result<Vec<u8>>,
) -> Result<Scene> {
    if json.views.is_empty() {
        return Err(Error::Json {
            file: scene_file.into(),
            problem: "the scene has no views".into(),
        });
    }
    let mut views = Vec::with_capacity(json.views.len());
    let mut warnings = Vec::new();
    for (i, vj) in json.views.iter().enumerate() {
        if json.views[..i].iter().any(|o| o.name == vj.name) {
            return Err(Error::Json {
                file: scene_file.into(),
                problem: format!("two views are named '{}'", vj.name),
            });
        }
        let (camera, warning) = vj.camera.to_camera_with_warning(&vj.name)?;
        warnings.extend(warning);
        let (w, h) = (camera.width, camera.height);
        let mask = decode_mask_sized(&fetch(&vj.mask)?, &vj.name, &vj.mask, w, h)?;
        let ignore = match &vj.ignore {
            None => None,
            Some(f) => Some(decode_mask_sized(&fetch(f)?, &vj.name, f, w, h)?),
        };
        let image = match &vj.image {
            None => None,
            Some(f) => Some(decode_image_sized(&fetch(f)?, &vj.name, f, w, h)?),
        };
        let sources = ViewSources::files(
            &vj.mask,
            vj.ignore.as_deref().unwrap_or(""),
            vj.image.as_deref().unwrap_or(""),
        );
        views.push(View::new(&vj.name, camera, mask, ignore, image, &sources)?);
    }
    let mut pose = |p: &Option<PoseJson>, key: &str| -> Result<Option<Pose>> {
        let Some(p) = p else { return Ok(None) };
        let (pose, deviation) = p.to_pose_with_warning().map_err(|e| Error::Json {
            file: scene_file.into(),
            problem: format!("{key}: {e}"),
        })?;
        if let Some(d) = deviation {
            warnings.push(format!(
                "{scene_file}: {key}: the rotation is off SO(3) by {d:.2e}: projected onto the nearest rotation"
            ));
        }
        Ok(Some(pose))
    };
    let initial_pose = pose(&json.initial_pose, "initial_pose")?;
    let ground_truth_pose = pose(&json.ground_truth_pose, "ground_truth_pose")?;
    Ok(Scene {
        warnings,
        initial_pose,
        ground_truth_pose,
        grasps: crate::io::grasp::grasps_from_json(&json.grasps, scene_file)?,
        mesh,
        views,
        json,
    })
}
