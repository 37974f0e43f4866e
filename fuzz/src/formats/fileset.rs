//! The file sets of the page (`FileSet`): layouts, their files and the file-set
//! driver.

use super::{
    camera_json, check_mesh, check_mesh_limits, check_scene, check_scene_limits, dump, jstr, mesh_files, nums,
    scene_files, text_of, MaskSpec, PngKind, SceneSpec,
};
use localisebot::io;
use localisebot::io::fileset::{FileRole, FileSet};
use localisebot::io::scene::Scene;
use localisebot::Limits;

// ---------------------------------------------------------------------------------
// The file sets of the page (`FileSet`)

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layout {
    /// The scene's folder as it is.
    Folder,
    /// Bare names (a file chooser).
    Bare,
    /// One camera `.json` per view (`wrapped`: a view entry with `camera`), masks named
    /// by `mask_style`, images by `image_style` (see [`fileset_files`]).
    PerView {
        wrapped: bool,
        mask_style: u8,
        image_style: u8,
    },
}

#[derive(Debug, Clone, PartialEq)]
pub struct FilesetSpec {
    pub scene: SceneSpec,
    pub layout: Layout,
    /// A folder above everything ("" or ending in `/`).
    pub prefix: String,
    /// More files, by path.
    pub junk: Vec<(String, Vec<u8>)>,
    /// Files given twice, the second time under a bare name (indices modulo the count).
    pub twice: Vec<usize>,
    /// The order the files are added in: a rotation of the list.
    pub rotate: usize,
}

/// Makes a scene fit one-camera-file-per-view: no poses or grasps (those files hold
/// none), no ignore masks; without `wrapped` (a bare camera, no box) a photo view gets
/// a mask instead.
pub fn per_view_ready(scene: &mut SceneSpec, wrapped: bool) {
    scene.initial_pose = None;
    scene.ground_truth = None;
    scene.grasps.clear();
    for v in &mut scene.views {
        v.ignore = None;
        if !wrapped && v.mask.is_none() {
            v.mask = v.image.as_ref().map(|im| MaskSpec {
                kind: PngKind::Gray8,
                width: im.width,
                height: im.height,
                bits: vec![1],
            });
            v.hint = None;
        }
    }
}

/// The files as a page hands them over, in order.
pub fn fileset_files(f: &FilesetSpec) -> Vec<(String, Vec<u8>)> {
    let mut out: Vec<(String, Vec<u8>)> = Vec::new();
    let sf = scene_files(&SceneSpec {
        dir: String::new(),
        ..f.scene.clone()
    });
    let base = |p: &str| p.rsplit('/').next().unwrap_or(p).to_string();
    match f.layout {
        Layout::Folder | Layout::Bare => {
            let bare = f.layout == Layout::Bare;
            let name = |p: &str| if bare { base(p) } else { format!("{}{p}", f.prefix) };
            out.push((name("scene.json"), sf.text.clone().into_bytes()));
            for (p, b) in &sf.files {
                out.push((name(p), b.clone()));
            }
        }
        Layout::PerView {
            wrapped,
            mask_style,
            image_style,
        } => {
            let p = &f.prefix;
            if let Some((mesh_name, mf)) = mesh_files(&f.scene.mesh, &f.scene.format, "model") {
                let _ = mesh_name;
                for (k, v) in mf {
                    out.push((format!("{p}{k}"), v));
                }
            }
            for v in &f.scene.views {
                let n = &v.name;
                let cam = camera_json(&v.camera);
                let text = if wrapped {
                    let mut s = format!("{{\"name\": {}, \"camera\": {cam}", jstr(n));
                    if let Some(b) = v.hint {
                        s += &format!(", \"box\": {}", nums(&b));
                    }
                    s + "}"
                } else {
                    cam
                };
                out.push((format!("{p}{n}.json"), text.into_bytes()));
                if let Some(m) = &v.mask {
                    let path = match mask_style % 4 {
                        0 => format!("{p}masks/{n}.png"),
                        1 => format!("{p}{n}_mask.png"),
                        2 => format!("{p}mask_{n}.png"),
                        _ => format!("{p}{n}.png"),
                    };
                    out.push((path, m.png()));
                }
                if let Some(im) = &v.image {
                    let path = match image_style % 3 {
                        0 => format!("{p}images/{n}.png"),
                        1 => format!("{p}{n}_image.png"),
                        _ => format!("{p}rgb/{n}.png"),
                    };
                    out.push((path, im.png()));
                }
            }
        }
    }
    let n = out.len();
    for &i in &f.twice {
        if n > 0 {
            let (p, b) = out[i % n].clone();
            out.push((base(&p), b));
        }
    }
    out.extend(f.junk.iter().cloned());
    if !out.is_empty() {
        let r = f.rotate % out.len();
        out.rotate_left(r);
    }
    out
}

/// Every call the binding makes on a set of these files, and finally
/// [`FileSet::load`] (checked when it accepts).
pub fn drive_fileset(
    files: &[(String, Vec<u8>)],
    limits: &Limits,
) -> localisebot::Result<(Scene, Vec<String>, String)> {
    let mut set = FileSet::new();
    for (i, (p, b)) in files.iter().enumerate() {
        dump(&format!("{i}-{p}"), b);
    }
    for (p, b) in files {
        set.add(p, b.clone());
    }
    set.set_limits(*limits);
    let names = set.names();
    assert!(names.len() <= files.len());
    for n in &names {
        for role in [FileRole::Mask, FileRole::Image, FileRole::Other] {
            let _ = set.find(n, role);
        }
    }
    for (p, b) in files {
        let lower = p.to_ascii_lowercase();
        if io::fileset::is_mesh_file(p) {
            let _ = io::fileset::mesh_references(p, b);
            if let Ok(m) = set.load_mesh(p, b) {
                check_mesh(&m);
                check_mesh_limits(p, &m, limits);
            }
        } else if lower.ends_with(".json") {
            let _ = io::fileset::scene_references(p, &text_of(b));
        }
    }
    let _ = set.needs_segmenter();
    if let Ok(io::fileset::Plan::Scene { file, text }) = set.plan() {
        if let Ok((s, _)) = set.load_scene(&file, &text) {
            check_scene(&s);
            check_scene_limits(&s, limits);
        }
    }
    let r = set.load();
    if let Ok((s, _, _)) = &r {
        check_scene(s);
        check_scene_limits(s, limits);
    }
    r
}
