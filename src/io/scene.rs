//! The scene file (`scene.json`, SPEC §3): its wire form [`SceneJson`], and
//! [`load_scene`], which resolves the mesh, masks and images it names into a
//! validated [`Scene`].

use crate::camera::CameraJson;
use crate::error::{Error, Result};
use crate::io::{join, load_mesh, mask::decode_image, mask::decode_mask, parent_dir, Resolver};
use crate::mesh::Mesh;
use crate::pose::{Pose, PoseJson};
use crate::view::View;
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
    pub grasps: Vec<crate::grasp::Grasp>,
    /// The file as read.
    pub json: SceneJson,
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
    for (i, vj) in json.views.iter().enumerate() {
        if json.views[..i].iter().any(|o| o.name == vj.name) {
            return Err(Error::Json {
                file: scene_file.into(),
                problem: format!("two views are named '{}'", vj.name),
            });
        }
        let camera = vj.camera.to_camera(&vj.name)?;
        let mask = decode_mask(&fetch(&vj.mask)?, &vj.name, &vj.mask)?;
        check_mask(&vj.name, &vj.mask, &mask, camera.width, camera.height)?;
        let image = match &vj.image {
            None => None,
            Some(f) => {
                let img = decode_image(&fetch(f)?, &vj.name, f)?;
                if (img.width, img.height) != (camera.width, camera.height) {
                    return Err(Error::Image {
                        view: vj.name.clone(),
                        file: f.clone(),
                        problem: format!(
                            "is {}×{} but the camera is {}×{}",
                            img.width, img.height, camera.width, camera.height
                        ),
                    });
                }
                Some(img)
            }
        };
        views.push(View {
            name: vj.name.clone(),
            camera,
            mask,
            image,
        });
    }
    let pose = |p: &Option<PoseJson>, key: &str| -> Result<Option<Pose>> {
        p.as_ref()
            .map(|p| {
                p.to_pose().map_err(|e| Error::Json {
                    file: scene_file.into(),
                    problem: format!("{key}: {e}"),
                })
            })
            .transpose()
    };
    Ok(Scene {
        initial_pose: pose(&json.initial_pose, "initial_pose")?,
        ground_truth_pose: pose(&json.ground_truth_pose, "ground_truth_pose")?,
        grasps: crate::grasp::grasps_from_json(&json.grasps, scene_file)?,
        mesh,
        views,
        json,
    })
}

/// Checks a mask's size against its camera and that it is not empty.
pub fn check_mask(view: &str, file: &str, mask: &crate::mask::Mask, width: u32, height: u32) -> Result<()> {
    let err = |p: String| Error::Mask {
        view: view.into(),
        file: file.into(),
        problem: p,
    };
    if (mask.width, mask.height) != (width, height) {
        return Err(err(format!(
            "is {}×{} but the camera is {}×{}",
            mask.width, mask.height, width, height
        )));
    }
    if mask.area() == 0 {
        return Err(err("is empty: no pixel is marked as object".into()));
    }
    Ok(())
}
