//! File-system helpers for the command line: reading and writing with messages
//! that name the path, and loading scenes, meshes and poses from disk.

use localisebot::{io, load_scene, Mesh, Pose, Scene};
use std::path::Path;

/// A command-line error: one line for the user.
pub type CliResult<T = ()> = Result<T, String>;

/// Reads a whole file, naming it in the error.
pub fn read(path: &Path) -> CliResult<Vec<u8>> {
    std::fs::read(path).map_err(|e| format!("{}: cannot read: {e}", path.display()))
}

/// Reads a UTF-8 text file.
pub fn read_text(path: &Path) -> CliResult<String> {
    String::from_utf8(read(path)?).map_err(|_| format!("{}: not UTF-8 text", path.display()))
}

/// Writes a file, creating its folder.
pub fn write(path: &Path, bytes: &[u8]) -> CliResult {
    if let Some(dir) = path.parent() {
        if !dir.as_os_str().is_empty() {
            std::fs::create_dir_all(dir).map_err(|e| format!("{}: cannot create folder: {e}", dir.display()))?;
        }
    }
    std::fs::write(path, bytes).map_err(|e| format!("{}: cannot write: {e}", path.display()))
}

/// Loads a mesh file; `.gltf` buffers are read from beside it.
pub fn load_mesh(path: &Path) -> CliResult<Mesh> {
    let bytes = read(path)?;
    let name = path.to_string_lossy();
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    io::load_mesh(&name, &bytes, &|uri| std::fs::read(dir.join(uri)).ok()).map_err(|e| e.to_string())
}

/// Loads a scene file and everything it names; prints the loader's warnings on stderr.
pub fn load_scene_file(path: &Path) -> CliResult<Scene> {
    let text = read_text(path)?;
    let scene = load_scene(&path.to_string_lossy(), &text, &|p| std::fs::read(p).ok()).map_err(|e| e.to_string())?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    Ok(scene)
}

/// [`load_scene_file`] for a command that needs every view's mask: a view without one
/// is an error naming it.
pub fn load_masked_scene_file(path: &Path, command: &str) -> CliResult<Scene> {
    let scene = load_scene_file(path)?;
    scene
        .require_masks(command)
        .map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(scene)
}

/// Loads a pose: a pose file, or a result file whose "pose" key holds one.
pub fn load_pose(path: &Path) -> CliResult<Pose> {
    let text = read_text(path)?;
    let name = path.to_string_lossy();
    let value: serde_json::Value = serde_json::from_str(&text).map_err(|e| format!("{name}: {e}"))?;
    let inner = match value.get("pose") {
        Some(p) if p.is_object() => p.to_string(),
        _ => text,
    };
    Pose::from_json_str(&inner, &name).map_err(|e| e.to_string())
}

/// Pretty JSON text of a serialisable value.
pub fn to_json<T: serde::Serialize>(v: &T) -> String {
    serde_json::to_string_pretty(v).expect("serialising plain data cannot fail")
}
