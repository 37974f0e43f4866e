//! NeRF / Blender `transforms*.json` folders (FORMATS.md §3) to the scene form
//! (SPEC §3): one view per frame whose image is present, the RGBA image's alpha as
//! the mask.
//!
//! Input: the transforms file's text and a resolver for the files it names (paths
//! joined onto the transforms file's folder). Output: an [`Imported`] scene — its
//! [`SceneJson`], the files to write beside it (`masks/NAME.png`, 8-bit 0/255;
//! `images/NAME.ext`, the original bytes) and warnings.
//!
//! Cameras: `transform_matrix` is camera-to-world with OpenGL axes, written as such
//! (`"convention": "opengl"`). Intrinsics, per frame over top level: `fl_x`/`fl_y`,
//! else `fx = fy = 0.5·w / tan(0.5·camera_angle_x)` (`camera_angle_y` gives fy);
//! `cx`, `cy` default to `w/2`, `h/2`; `w`, `h` default to the image's size. These
//! files put pixel centres at half-integers (Blender renders, nerfstudio and
//! instant-ngp shoot rays through `i + 0.5`), SPEC §2 at integers, so the written
//! principal point is `cx − 0.5`, `cy − 0.5` (lego: 399.5). The original NeRF code
//! casts rays through integer indices with `cx = W/2`, half a pixel off the renders.
//! Where `w`, `h` differ from the image, intrinsics are rescaled to the image.

use crate::camera::{CameraJson, Convention};
use crate::error::{Error, Result};
use crate::io::mask::{decode_image, decode_mask, mask_from_rgba};
use crate::io::png::encode_gray;
use crate::io::scene::{SceneJson, ViewJson};
use crate::io::{join, parent_dir, Resolver};
use crate::mask::Mask;
use serde::Deserialize;

/// An imported scene: the scene file's content, the files it refers to, and what
/// was skipped or ignored.
#[derive(Debug, Clone)]
pub struct Imported {
    /// The scene (views, cameras, mesh path, optional ground truth).
    pub scene: SceneJson,
    /// Files to write, as (path relative to the scene file, bytes): masks, images and,
    /// for BOP, the mesh.
    pub files: Vec<(String, Vec<u8>)>,
    /// Frames skipped and data ignored, one sentence each.
    pub warnings: Vec<String>,
}

/// Intrinsic keys, at the top level or per frame (instant-ngp / nerfstudio extensions).
#[derive(Debug, Clone, Default, Deserialize)]
struct Intrinsics {
    camera_angle_x: Option<f64>,
    camera_angle_y: Option<f64>,
    fl_x: Option<f64>,
    fl_y: Option<f64>,
    cx: Option<f64>,
    cy: Option<f64>,
    w: Option<f64>,
    h: Option<f64>,
    k1: Option<f64>,
    k2: Option<f64>,
    k3: Option<f64>,
    k4: Option<f64>,
    p1: Option<f64>,
    p2: Option<f64>,
}

impl Intrinsics {
    /// These values, each falling back to `base`'s.
    fn over(&self, base: &Intrinsics) -> Intrinsics {
        Intrinsics {
            camera_angle_x: self.camera_angle_x.or(base.camera_angle_x),
            camera_angle_y: self.camera_angle_y.or(base.camera_angle_y),
            fl_x: self.fl_x.or(base.fl_x),
            fl_y: self.fl_y.or(base.fl_y),
            cx: self.cx.or(base.cx),
            cy: self.cy.or(base.cy),
            w: self.w.or(base.w),
            h: self.h.or(base.h),
            k1: self.k1.or(base.k1),
            k2: self.k2.or(base.k2),
            k3: self.k3.or(base.k3),
            k4: self.k4.or(base.k4),
            p1: self.p1.or(base.p1),
            p2: self.p2.or(base.p2),
        }
    }

    fn has_distortion(&self) -> bool {
        [self.k1, self.k2, self.k3, self.k4, self.p1, self.p2]
            .iter()
            .any(|k| k.is_some_and(|v| v != 0.0))
    }
}

#[derive(Debug, Deserialize)]
struct Frame {
    file_path: String,
    transform_matrix: [[f64; 4]; 4],
    #[serde(default)]
    mask_path: Option<String>,
    #[serde(flatten)]
    intrinsics: Intrinsics,
}

#[derive(Debug, Deserialize)]
struct Transforms {
    frames: Vec<Frame>,
    #[serde(flatten)]
    intrinsics: Intrinsics,
}

/// Imports a `transforms*.json` (the file `transforms_file`, content `text`).
/// `files` supplies images and masks by path joined onto the transforms file's
/// folder; `mesh_file` is written as the scene's mesh (NeRF folders have none).
/// Frames whose image is missing, or whose mask would be empty, are skipped with a
/// warning; an invalid camera is an error naming the frame.
pub fn import(transforms_file: &str, text: &str, files: Resolver, mesh_file: &str) -> Result<Imported> {
    let json_err = |problem: String| Error::Json {
        file: transforms_file.into(),
        problem,
    };
    crate::limits::check_json_depth(transforms_file, text.as_bytes())?;
    let t: Transforms = serde_json::from_str(text).map_err(|e| json_err(e.to_string()))?;
    let dir = parent_dir(transforms_file);
    let mut out = Imported {
        scene: SceneJson {
            version: 1,
            mesh: mesh_file.into(),
            views: Vec::new(),
            initial_pose: None,
            ground_truth_pose: None,
            grasps: Vec::new(),
        },
        files: Vec::new(),
        warnings: Vec::new(),
    };
    let mut distortion = false;
    for frame in &t.frames {
        let k = frame.intrinsics.over(&t.intrinsics);
        distortion |= k.has_distortion();
        let Some((image_path, image_bytes)) = find_image(dir, &frame.file_path, files) else {
            out.warnings.push(format!(
                "frame '{}': image not found (tried {}); skipped",
                frame.file_path,
                candidates(&frame.file_path).join(", ")
            ));
            continue;
        };
        let name = unique_name(&out.scene.views, &frame.file_path);
        let image = decode_image(&image_bytes, &name, &image_path)?;
        let mask = match &frame.mask_path {
            Some(m) => {
                let bytes = files(&join(dir, m)).ok_or_else(|| Error::MissingFile {
                    file: join(dir, m),
                    referrer: format!("{transforms_file}, frame '{}'", frame.file_path),
                })?;
                decode_mask(&bytes, &name, m)?
            }
            None if image.data.chunks_exact(4).all(|p| p[3] == 255) => {
                out.warnings.push(format!(
                    "frame '{}': {image_path} has no transparent pixel, so no mask; skipped",
                    frame.file_path
                ));
                continue;
            }
            None => mask_from_rgba(&image),
        };
        if (mask.width, mask.height) != (image.width, image.height) {
            return Err(Error::Mask {
                view: name,
                file: frame.mask_path.clone().unwrap_or_default(),
                problem: format!(
                    "is {}×{} but the image is {}×{}",
                    mask.width, mask.height, image.width, image.height
                ),
            });
        }
        if mask.area() == 0 {
            out.warnings
                .push(format!("frame '{}': the mask is empty; skipped", frame.file_path));
            continue;
        }
        let camera = camera(&k, image.width, image.height, frame.transform_matrix).map_err(|p| Error::Camera {
            view: name.clone(),
            problem: p,
        })?;
        camera.to_camera(&name)?;
        if k.w.is_some_and(|w| w != image.width as f64) || k.h.is_some_and(|h| h != image.height as f64) {
            out.warnings.push(format!(
                "frame '{}': intrinsics given for {}×{} were rescaled to the {}×{} image",
                frame.file_path,
                k.w.unwrap_or(image.width as f64),
                k.h.unwrap_or(image.height as f64),
                image.width,
                image.height
            ));
        }
        let ext = image_path.rsplit_once('.').map_or("png", |(_, e)| e);
        let (mask_rel, image_rel) = (format!("masks/{name}.png"), format!("images/{name}.{ext}"));
        out.files.push((mask_rel.clone(), mask_png(&mask)));
        out.files.push((image_rel.clone(), image_bytes));
        out.scene.views.push(ViewJson {
            ignore: None,
            name,
            image: Some(image_rel),
            mask: Some(mask_rel),
            hint_box: None,
            camera,
        });
    }
    if distortion {
        out.warnings
            .push("lens distortion coefficients are ignored: the cameras are taken as pinholes".into());
    }
    if out.scene.views.is_empty() {
        return Err(json_err(format!(
            "none of its {} frames has an image with a mask",
            t.frames.len()
        )));
    }
    Ok(out)
}

/// A mask as an 8-bit PNG, object 255 and background 0.
pub fn mask_png(mask: &Mask) -> Vec<u8> {
    let data: Vec<u8> = mask.data.iter().map(|&v| if v != 0 { 255 } else { 0 }).collect();
    encode_gray(mask.width, mask.height, &data)
}

/// The paths tried for a frame's image: as written, then with `.png` if it has no extension.
fn candidates(file_path: &str) -> Vec<String> {
    let file_name = file_path.rsplit(['/', '\\']).next().unwrap_or(file_path);
    let mut c = vec![file_path.to_string()];
    if !file_name.contains('.') {
        c.push(format!("{file_path}.png"));
    }
    c
}

fn find_image(dir: &str, file_path: &str, files: Resolver) -> Option<(String, Vec<u8>)> {
    candidates(file_path).into_iter().find_map(|c| {
        let p = join(dir, &c);
        files(&p).map(|b| (p, b))
    })
}

/// The frame's file stem (`./train/r_0` → `r_0`), made unique among `views`.
fn unique_name(views: &[ViewJson], file_path: &str) -> String {
    let file_name = file_path.rsplit(['/', '\\']).next().unwrap_or(file_path);
    let stem = match file_name.rsplit_once('.') {
        Some((s, _)) if !s.is_empty() => s,
        _ => file_name,
    };
    let stem = if stem.is_empty() { "view" } else { stem };
    let mut name = stem.to_string();
    let mut k = 2;
    while views.iter().any(|v| v.name == name) {
        name = format!("{stem}_{k}");
        k += 1;
    }
    name
}

/// The camera of a frame whose image is `width`×`height`.
fn camera(k: &Intrinsics, width: u32, height: u32, c2w: [[f64; 4]; 4]) -> std::result::Result<CameraJson, String> {
    let (w, h) = (k.w.unwrap_or(width as f64), k.h.unwrap_or(height as f64));
    if !(w > 0.0 && h > 0.0) {
        return Err(format!("w and h must be positive (got {w}, {h})"));
    }
    let from_angle = |size: f64, angle: Option<f64>| angle.map(|a| 0.5 * size / (0.5 * a).tan());
    let fx = k
        .fl_x
        .or(from_angle(w, k.camera_angle_x))
        .ok_or("no focal length: needs fl_x or camera_angle_x")?;
    let fy = k.fl_y.or(from_angle(h, k.camera_angle_y)).unwrap_or(fx);
    // Principal point with pixel centres at half-integers, then rescaled to the image.
    let (cx, cy) = (k.cx.unwrap_or(0.5 * w), k.cy.unwrap_or(0.5 * h));
    let (sx, sy) = (width as f64 / w, height as f64 / h);
    Ok(CameraJson {
        width,
        height,
        fx: fx * sx,
        fy: fy * sy,
        cx: cx * sx - 0.5,
        cy: cy * sy - 0.5,
        world_to_camera: None,
        camera_to_world: Some(c2w),
        convention: Convention::Opengl,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::png::encode_rgba;
    use crate::view::Rgba;
    use glam::DVec3;
    use std::collections::HashMap;

    /// A 20×10 RGBA image: alpha 255 on columns 5..15 of rows 2..8, 0 elsewhere.
    fn rgba(alpha_outside: u8) -> Vec<u8> {
        let mut data = Vec::new();
        for y in 0..10 {
            for x in 0..20 {
                let inside = (5..15).contains(&x) && (2..8).contains(&y);
                data.extend([10, 20, 30, if inside { 255 } else { alpha_outside }]);
            }
        }
        encode_rgba(&Rgba {
            width: 20,
            height: 10,
            data,
        })
    }

    const C2W: &str = "[[1,0,0,0],[0,1,0,0],[0,0,1,4],[0,0,0,1]]";

    #[test]
    fn frames_views_masks_and_intrinsics() {
        let files: HashMap<String, Vec<u8>> = [
            ("data/a.png".to_string(), rgba(0)),
            ("data/sub/b.png".to_string(), rgba(0)),
            ("data/opaque.png".to_string(), rgba(255)),
        ]
        .into();
        let text = format!(
            r#"{{"camera_angle_x": 1.0, "frames": [
              {{"file_path": "./a", "transform_matrix": {C2W}}},
              {{"file_path": "sub/b.png", "transform_matrix": {C2W}, "fl_x": 30, "cx": 9, "w": 40, "h": 20}},
              {{"file_path": "./missing", "transform_matrix": {C2W}}},
              {{"file_path": "./opaque", "transform_matrix": {C2W}}}]}}"#
        );
        let imp = import("data/transforms.json", &text, &|p| files.get(p).cloned(), "box.glb").unwrap();
        let names: Vec<&str> = imp.scene.views.iter().map(|v| v.name.as_str()).collect();
        assert_eq!(names, ["a", "b"]);
        assert_eq!(imp.warnings.len(), 3, "{:?}", imp.warnings);
        assert!(imp.warnings[0].contains("sub/b.png") && imp.warnings[0].contains("rescaled"));
        assert!(imp.warnings[1].contains("./missing") && imp.warnings[2].contains("no transparent"));
        let a = &imp.scene.views[0].camera;
        assert!((a.fx - 10.0 / (0.5f64).tan()).abs() < 1e-12 && a.fy == a.fx);
        assert_eq!((a.cx, a.cy), (9.5, 4.5));
        // b: intrinsics for 40×20, image 20×10: halved, principal point 9 → 4.5 → 4.0.
        let b = &imp.scene.views[1].camera;
        assert_eq!((b.fx, b.fy, b.cx, b.cy), (15.0, 15.0, 4.0, 4.5));
        // The camera looks down world −z from z = 4 (OpenGL), so the origin is ahead of it.
        let cam = b.to_camera("b").unwrap();
        assert!((cam.to_camera(DVec3::ZERO) - DVec3::new(0.0, 0.0, 4.0)).length() < 1e-12);
        let mask_bytes = &imp.files.iter().find(|(p, _)| p == "masks/a.png").unwrap().1;
        let mask = decode_mask(mask_bytes, "a", "masks/a.png").unwrap();
        assert_eq!(mask.area(), 60);
        assert!(mask.get(5, 2) && !mask.get(4, 2) && !mask.get(5, 8));
        assert_eq!(imp.files.iter().find(|(p, _)| p == "images/b.png").unwrap().1, rgba(0));
    }

    #[test]
    fn bad_input_is_named() {
        let none = |_: &str| None;
        let e = import("t.json", "{", &none, "m.glb").unwrap_err().to_string();
        assert!(e.starts_with("t.json: "), "{e}");
        let text = format!(r#"{{"frames": [{{"file_path": "./x", "transform_matrix": {C2W}}}]}}"#);
        let e = import("t.json", &text, &none, "m.glb").unwrap_err().to_string();
        assert!(e.contains("none of its 1 frames"), "{e}");
        let png = rgba(0);
        let e = import("t.json", &text, &|_| Some(png.clone()), "m.glb")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("view 'x': camera: no focal length"), "{e}");
    }
}
