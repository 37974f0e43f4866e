//! The scene file (`scene.json`, SPEC §3): its wire form [`SceneJson`], and
//! [`load_scene`], which resolves the mesh, masks and images it names into a
//! validated [`Scene`].

use crate::camera::CameraJson;
use crate::error::{Error, Result};
use crate::io::mask::{decode_image_sized, decode_mask_sized};
use crate::io::{join, load_mesh_with, parent_dir, Resolver};
use crate::limits::Limits;
use crate::mesh::Mesh;
use crate::pose::{Pose, PoseJson};
use crate::view::{PhotoView, PixelBox, View, ViewSources};
use serde::{Deserialize, Serialize};

/// One view's entry in the scene file.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct ViewJson {
    /// Unique name.
    pub name: String,
    /// Optional photograph, relative to the scene file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub image: Option<String>,
    /// Mask PNG, relative to the scene file. Without one, the view's mask is made from
    /// its `image` (see `box`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mask: Option<String>,
    /// A rough box around the object in the image, `[x_min, y_min, x_max, y_max]`
    /// pixels (covering `x_min ≤ x < x_max`, `y_min ≤ y < y_max`), for a view without a
    /// mask; a view with an image and neither box nor mask gets its box from the
    /// geometry of at least two others.
    #[serde(default, rename = "box", skip_serializing_if = "Option::is_none")]
    pub hint_box: Option<[f64; 4]>,
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
    /// The views with masks, in file order.
    pub views: Vec<View>,
    /// The views whose masks are to be made from their photographs (a box, or the
    /// geometry), in file order; empty for a scene of masks.
    pub photos: Vec<PhotoView>,
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

impl Scene {
    /// Checks that a view with neither a box nor a mask can be placed: its box comes
    /// from the geometry of at least two other views with one. ([`load_scene`] checks
    /// it; a page where boxes are still to be drawn loads first and checks when the
    /// fit starts.)
    ///
    /// Errors: naming the first such view.
    pub fn check_hints(&self) -> Result<()> {
        let hinted = self.views.len() + self.photos.iter().filter(|p| p.hint.is_some()).count();
        match self.photos.iter().find(|p| p.hint.is_none()) {
            Some(p) if hinted < 2 => Err(Error::View {
                view: p.name.clone(),
                problem: format!(
                    "has neither a mask nor a box, and its box can only come from the geometry of at least two \
                     other views with a box or a mask (the scene has {hinted})"
                ),
            }),
            _ => Ok(()),
        }
    }

    /// An error naming the first view whose mask is still to be made (for what needs
    /// every view's mask: `what` says who asks).
    pub fn require_masks(&self, what: &str) -> Result<()> {
        match self.photos.first() {
            None => Ok(()),
            Some(p) => Err(Error::View {
                view: p.name.clone(),
                problem: format!(
                    "has no mask (a photograph{}): {what} needs every view's mask — make them with \
                     `localisebot segment`, or fit the scene with `localisebot fit`, which makes them",
                    if p.hint.is_some() { " and a box" } else { "" }
                ),
            }),
        }
    }
}

impl SceneJson {
    /// Parses scene JSON text; `file` names it in errors.
    pub fn parse(text: &str, file: &str) -> Result<SceneJson> {
        crate::limits::check_json_depth(file, text.as_bytes())?;
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
    load_scene_with(scene_file, text, files, &Limits::DEFAULT)
}

/// As [`load_scene`], every size checked against `limits` (the views, their pixels,
/// the mesh's counts, each file's bytes) before it is decoded.
pub fn load_scene_with(scene_file: &str, text: &str, files: Resolver, limits: &Limits) -> Result<Scene> {
    limits.check_file(scene_file, text.len() as u64)?;
    let json = SceneJson::parse(text, scene_file)?;
    limits.check_views(scene_file, json.views.len() as u64)?;
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
    let mesh = load_mesh_with(&mesh_path, &mesh_bytes, &|uri| files(&join(&mesh_dir, uri)), limits)?;
    let scene = scene_from_parts(scene_file, json, mesh, &|rel| fetch(rel, scene_file), limits)?;
    scene.check_hints()?;
    Ok(scene)
}

/// Builds a scene from its parsed JSON and an already loaded mesh; `fetch` supplies
/// each mask and image by the path written in the scene.
pub fn scene_from_parts(
    scene_file: &str,
    json: SceneJson,
    mesh: Mesh,
    fetch: &dyn Fn(&str) -> Result<Vec<u8>>,
    limits: &Limits,
) -> Result<Scene> {
    if json.views.is_empty() {
        return Err(Error::Json {
            file: scene_file.into(),
            problem: "the scene has no views".into(),
        });
    }
    limits.check_views(scene_file, json.views.len() as u64)?;
    // Every camera's pixels, before any mask or image is fetched or decoded.
    let mut total = 0u64;
    for vj in &json.views {
        total += vj.camera.width as u64 * vj.camera.height as u64;
        limits.check_pixels(&vj.name, vj.camera.width, vj.camera.height, total)?;
    }
    let fetch = |rel: &str| -> Result<Vec<u8>> {
        let bytes = fetch(rel)?;
        limits.check_file(rel, bytes.len() as u64)?;
        Ok(bytes)
    };
    let mut views = Vec::with_capacity(json.views.len());
    let mut photos = Vec::new();
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
        let ignore = match &vj.ignore {
            None => None,
            Some(f) => Some(decode_mask_sized(&fetch(f)?, &vj.name, f, w, h)?),
        };
        let image = match &vj.image {
            None => None,
            Some(f) => Some(decode_image_sized(&fetch(f)?, &vj.name, f, w, h)?),
        };
        let hint = vj.hint_box.map(|b| PixelBox::new(&vj.name, b, w, h)).transpose()?;
        let Some(mask_file) = &vj.mask else {
            let problem = match (&image, hint) {
                (None, Some(_)) => "has a box but no image: a box says where the object is in the view's photograph",
                (None, None) => "has neither a mask nor an image",
                (Some(_), _) => "",
            };
            if !problem.is_empty() {
                return Err(Error::View {
                    view: vj.name.clone(),
                    problem: problem.into(),
                });
            }
            photos.push(PhotoView {
                name: vj.name.clone(),
                camera,
                image: image.expect("checked above").into(),
                ignore,
                hint,
                index: i,
            });
            continue;
        };
        let mask = decode_mask_sized(&fetch(mask_file)?, &vj.name, mask_file, w, h)?;
        let sources = ViewSources::files(
            mask_file,
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
        photos,
        json,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::png::{encode_gray, encode_rgba};
    use crate::view::Rgba;

    /// A scene of three 32×24 views whose entries are `views` (JSON objects without the
    /// camera), with a mask, an image and a mesh to resolve.
    fn scene(views: &[&str]) -> Result<Scene> {
        let camera = r#"{"width": 32, "height": 24, "fx": 30, "fy": 30, "cx": 15.5, "cy": 11.5,
            "world_to_camera": [[1,0,0,0],[0,1,0,0],[0,0,1,2],[0,0,0,1]]}"#;
        let entries: Vec<String> = views.iter().map(|v| format!("{{{v}, \"camera\": {camera}}}")).collect();
        let text = format!(r#"{{"mesh": "m.obj", "views": [{}]}}"#, entries.join(","));
        let mut mask = vec![0u8; 32 * 24];
        mask[12 * 32 + 16] = 255;
        let files = move |p: &str| -> Option<Vec<u8>> {
            match p {
                "m.obj" => Some(b"v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nf 1 2 3\n".to_vec()),
                "mask.png" => Some(encode_gray(32, 24, &mask)),
                "photo.png" => Some(encode_rgba(&Rgba {
                    width: 32,
                    height: 24,
                    data: vec![128; 32 * 24 * 4],
                })),
                _ => None,
            }
        };
        load_scene("scene.json", &text, &files)
    }

    #[test]
    fn views_may_give_a_photograph_and_a_box_instead_of_a_mask() {
        let s = scene(&[
            r#""name": "a", "mask": "mask.png""#,
            r#""name": "b", "image": "photo.png", "box": [4, 3, 20.5, 18]"#,
            r#""name": "c", "image": "photo.png""#,
        ])
        .unwrap();
        assert_eq!(s.views.len(), 1);
        assert_eq!(s.photos.len(), 2);
        assert_eq!((s.photos[0].name.as_str(), s.photos[0].index), ("b", 1));
        assert_eq!(s.photos[0].hint.unwrap().to_array(), [4.0, 3.0, 20.5, 18.0]);
        assert_eq!((s.photos[1].hint, s.photos[1].index), (None, 2));
        let e = s.require_masks("render").unwrap_err().to_string();
        assert!(
            e.contains("view 'b'") && e.contains("render needs every view's mask"),
            "{e}"
        );
        // The box survives a round trip through the wire form.
        let back = SceneJson::parse(&s.json.to_json_string(), "x").unwrap();
        assert_eq!(back.views[1].hint_box, Some([4.0, 3.0, 20.5, 18.0]));
    }

    #[test]
    fn bad_hints_are_named() {
        for (views, says) in [
            (
                vec![
                    r#""name": "a", "mask": "mask.png""#,
                    r#""name": "b", "box": [1, 1, 9, 9]"#,
                ],
                "view 'b': has a box but no image",
            ),
            (
                vec![r#""name": "a", "mask": "mask.png""#, r#""name": "b""#],
                "view 'b': has neither a mask nor an image",
            ),
            (
                vec![r#""name": "a", "image": "photo.png", "box": [9, 1, 2, 9]"#],
                "view 'a': box [9.0, 1.0, 2.0, 9.0]: is empty or inverted",
            ),
            (
                vec![r#""name": "a", "image": "photo.png", "box": [40, 1, 50, 9]"#],
                "overlap the image",
            ),
            (
                vec![
                    r#""name": "a", "mask": "mask.png""#,
                    r#""name": "b", "image": "photo.png""#,
                ],
                "view 'b': has neither a mask nor a box, and its box can only come from the geometry of at least two",
            ),
        ] {
            let e = scene(&views).unwrap_err().to_string();
            assert!(e.contains(says), "{e}\n  expected: {says}");
        }
        // JSON that is not a box at all is the parser's error, naming the file.
        let e = scene(&[r#""name": "a", "image": "photo.png", "box": [1, 2, 3]"#])
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("scene.json:"), "{e}");
    }
}
