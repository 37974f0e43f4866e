//! NeRF folders: the spec, its files, the NeRF importer's driver and the loading
//! of an import.

use super::{check_imported, check_scene, dump, dump_files, jstr, num, resolver, rows4, Files, ImageSpec, MaskSpec};
use localisebot::io::nerf::Imported;
use localisebot::io::scene::{load_scene_with, Scene};
use localisebot::io::{self, join};
use localisebot::Limits;

// ---------------------------------------------------------------------------------
// NeRF

#[derive(Debug, Clone, PartialEq, Default)]
pub struct NerfIntrinsics {
    pub camera_angle_x: Option<f64>,
    pub camera_angle_y: Option<f64>,
    pub fl_x: Option<f64>,
    pub fl_y: Option<f64>,
    pub cx: Option<f64>,
    pub cy: Option<f64>,
    pub w: Option<f64>,
    pub h: Option<f64>,
    pub k1: Option<f64>,
}

impl NerfIntrinsics {
    fn json_parts(&self) -> Vec<String> {
        let mut p = Vec::new();
        for (k, v) in [
            ("camera_angle_x", self.camera_angle_x),
            ("camera_angle_y", self.camera_angle_y),
            ("fl_x", self.fl_x),
            ("fl_y", self.fl_y),
            ("cx", self.cx),
            ("cy", self.cy),
            ("w", self.w),
            ("h", self.h),
            ("k1", self.k1),
        ] {
            if let Some(v) = v {
                p.push(format!("\"{k}\": {}", num(v)));
            }
        }
        p
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct NerfFrame {
    /// The frame's `file_path` (without `.png`, as Blender writes it, unless `with_ext`).
    pub file_path: String,
    pub with_ext: bool,
    pub matrix: [[f64; 4]; 4],
    pub intrinsics: NerfIntrinsics,
    /// The image (`file_path` + `.png`); absent: the frame's image is missing.
    pub image: Option<ImageSpec>,
    /// A `mask_path` and its PNG.
    pub mask: Option<MaskSpec>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct NerfSpec {
    /// The transforms file's folder ("" or ending in `/`).
    pub dir: String,
    pub intrinsics: NerfIntrinsics,
    pub frames: Vec<NerfFrame>,
}

/// (transforms file, its text, the files it names by path).
pub fn nerf_files(s: &NerfSpec) -> (String, String, Files) {
    let mut files = Files::new();
    let mut frames = Vec::new();
    for (i, f) in s.frames.iter().enumerate() {
        let path = if f.with_ext {
            format!("{}.png", f.file_path)
        } else {
            f.file_path.clone()
        };
        let mut parts = vec![
            format!("\"file_path\": {}", jstr(&path)),
            format!("\"transform_matrix\": {}", rows4(&f.matrix)),
        ];
        parts.extend(f.intrinsics.json_parts());
        if let Some(im) = &f.image {
            files.insert(join(&s.dir, &format!("{}.png", f.file_path)), im.png());
        }
        if let Some(m) = &f.mask {
            let rel = format!("masks/f{i}.png");
            parts.push(format!("\"mask_path\": {}", jstr(&rel)));
            files.insert(join(&s.dir, &rel), m.png());
        }
        frames.push(format!("{{{}}}", parts.join(", ")));
    }
    let mut top = s.intrinsics.json_parts();
    top.push(format!("\"frames\": [\n  {}\n]", frames.join(",\n  ")));
    (
        join(&s.dir, "transforms.json"),
        format!("{{{}}}\n", top.join(", ")),
        files,
    )
}

/// The NeRF import as `localisebot import-nerf` runs it; checks what it makes.
pub fn drive_nerf(transforms: &str, text: &str, files: &Files) -> localisebot::Result<Imported> {
    dump(transforms, text.as_bytes());
    dump_files(files);
    let r = io::nerf::import(transforms, text, &resolver(files), "mesh.ply");
    if let Ok(im) = &r {
        check_imported(im);
    }
    r
}

/// Loads an import's scene (with `mesh` as its mesh file when it names none of its
/// own), as the CLI does after writing it out.
pub fn load_imported(im: &Imported, mesh: Option<(&str, Vec<u8>)>) -> localisebot::Result<Scene> {
    let mut files: Files = im.files.iter().cloned().collect();
    if let Some((name, bytes)) = mesh {
        files.insert(name.to_string(), bytes);
    }
    let text = im.scene.to_json_string();
    let r = load_scene_with("scene.json", &text, &resolver(&files), &Limits::DEFAULT);
    if let Ok(s) = &r {
        check_scene(s);
    }
    r
}
