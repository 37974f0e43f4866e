//! Scenes: the scene spec, its files and the scene driver.

use super::{
    camera_json, check_scene, check_scene_limits, dump, dump_files, grasp_json, jstr, mesh_files, nums, pose_json,
    resolver, CamSpec, Files, GraspSpec, ImageSpec, MaskSpec, MeshFormat, MeshSpec, PoseSpec,
};
use localisebot::io::join;
use localisebot::io::scene::{load_scene_with, Scene};
use localisebot::Limits;

// ---------------------------------------------------------------------------------
// Scenes

#[derive(Debug, Clone, PartialEq)]
pub struct ViewSpec {
    pub name: String,
    pub camera: CamSpec,
    pub mask: Option<MaskSpec>,
    pub image: Option<ImageSpec>,
    pub ignore: Option<MaskSpec>,
    pub hint: Option<[f64; 4]>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct SceneSpec {
    /// The scene file's folder ("" or ending in `/`).
    pub dir: String,
    /// The mesh's folder relative to the scene ("" or ending in `/`).
    pub mesh_dir: String,
    pub version: Option<i64>,
    pub views: Vec<ViewSpec>,
    pub mesh: MeshSpec,
    pub format: MeshFormat,
    pub initial_pose: Option<PoseSpec>,
    pub ground_truth: Option<PoseSpec>,
    pub grasps: Vec<GraspSpec>,
}

/// A scene file, and the files it names, by path.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneFiles {
    pub scene_file: String,
    pub text: String,
    pub files: Files,
}

/// The view's JSON entry and its files (relative to the scene's folder).
fn view_entry(i: usize, v: &ViewSpec, files: &mut Vec<(String, Vec<u8>)>) -> String {
    let mut s = format!("{{\"name\": {}", jstr(&v.name));
    if let Some(m) = &v.mask {
        let rel = format!("masks/m{i}.png");
        s += &format!(", \"mask\": {}", jstr(&rel));
        files.push((rel, m.png()));
    }
    if let Some(im) = &v.image {
        let rel = format!("images/i{i}.png");
        s += &format!(", \"image\": {}", jstr(&rel));
        files.push((rel, im.png()));
    }
    if let Some(m) = &v.ignore {
        let rel = format!("masks/ignore{i}.png");
        s += &format!(", \"ignore\": {}", jstr(&rel));
        files.push((rel, m.png()));
    }
    if let Some(b) = v.hint {
        s += &format!(", \"box\": {}", nums(&b));
    }
    s + &format!(", \"camera\": {}}}", camera_json(&v.camera))
}

/// The scene's files: `scene.json` in `dir`, the masks and images beside it, the
/// mesh in `mesh_dir` (a mesh the project's writer refuses is left out).
pub fn scene_files(s: &SceneSpec) -> SceneFiles {
    let mut rel_files = Vec::new();
    let views: Vec<String> = s
        .views
        .iter()
        .enumerate()
        .map(|(i, v)| view_entry(i, v, &mut rel_files))
        .collect();
    let mut files = Files::new();
    let mut mesh_rel = format!("{}mesh.ply", s.mesh_dir);
    if let Some((name, mf)) = mesh_files(&s.mesh, &s.format, "mesh") {
        mesh_rel = format!("{}{name}", s.mesh_dir);
        for (k, v) in mf {
            files.insert(join(&join(&s.dir, &s.mesh_dir), &k), v);
        }
    }
    for (k, v) in rel_files {
        files.insert(join(&s.dir, &k), v);
    }
    let mut text = "{".to_string();
    if let Some(v) = s.version {
        text += &format!("\"version\": {v}, ");
    }
    text += &format!(
        "\"mesh\": {}, \"views\": [\n  {}\n]",
        jstr(&mesh_rel),
        views.join(",\n  ")
    );
    if let Some(p) = &s.initial_pose {
        text += &format!(", \"initial_pose\": {}", pose_json(p));
    }
    if let Some(p) = &s.ground_truth {
        text += &format!(", \"ground_truth_pose\": {}", pose_json(p));
    }
    if !s.grasps.is_empty() {
        let g: Vec<String> = s.grasps.iter().map(grasp_json).collect();
        text += &format!(", \"grasps\": [{}]", g.join(", "));
    }
    text += "}\n";
    SceneFiles {
        scene_file: join(&s.dir, "scene.json"),
        text,
        files,
    }
}

/// Loads a scene as `localisebot fit scene.json` does; checks an accepted scene.
pub fn drive_scene(sf: &SceneFiles, limits: &Limits) -> localisebot::Result<Scene> {
    dump(&sf.scene_file, sf.text.as_bytes());
    dump_files(&sf.files);
    let r = load_scene_with(&sf.scene_file, &sf.text, &resolver(&sf.files), limits);
    if let Ok(s) = &r {
        check_scene(s);
        check_scene_limits(s, limits);
    }
    r
}
