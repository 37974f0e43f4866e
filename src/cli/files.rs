//! File-system helpers for the command line: reading and writing with messages
//! that name the path, and loading scenes, meshes and poses from disk.

use localisebot::io::scene::load_scene_with;
use localisebot::{io, Limits, Mesh, Pose, Scene};
use std::cell::RefCell;
use std::path::Path;
use std::sync::OnceLock;

/// A command-line error: one line for the user.
pub type CliResult<T = ()> = Result<T, String>;

static LIMITS: OnceLock<Limits> = OnceLock::new();

/// Sets the process's limits from `--limit NAME=VALUE` options (once, at start).
pub fn set_limits(options: &[String]) -> CliResult {
    let mut l = Limits::DEFAULT;
    for o in options {
        l.set_text(o).map_err(|e| e.to_string())?;
    }
    LIMITS.set(l).map_err(|_| "limits set twice".to_string())
}

/// The limits every file this process reads is checked against.
pub fn limits() -> &'static Limits {
    LIMITS.get_or_init(|| Limits::DEFAULT)
}

/// Checks a file's size on disk against the limit before it is read.
fn check_size(path: &Path) -> CliResult {
    if let Ok(m) = std::fs::metadata(path) {
        limits()
            .check_file(&path.display().to_string(), m.len())
            .map_err(|e| e.to_string())?;
    }
    Ok(())
}

/// Reads a whole file, naming it in the error; a file over the size limit is refused
/// before it is read.
pub fn read(path: &Path) -> CliResult<Vec<u8>> {
    check_size(path)?;
    std::fs::read(path).map_err(|e| format!("{}: cannot read: {e}", path.display()))
}

/// A resolver over the disk for the loaders: a file that is missing or unreadable is
/// `None` (the loader names it), one over the size limit too, its refusal kept so
/// that [`Disk::explain`] can say it instead of "not found".
#[derive(Default)]
pub struct Disk {
    refused: RefCell<Option<String>>,
}

impl Disk {
    /// The bytes of `path`, if it exists and is within the size limit.
    pub fn get(&self, path: &Path) -> Option<Vec<u8>> {
        match check_size(path) {
            Ok(()) => std::fs::read(path).ok(),
            Err(e) => {
                self.refused.borrow_mut().get_or_insert(e);
                None
            }
        }
    }

    /// The message of a load's error: the size refusal that caused it, if any.
    pub fn explain(&self, e: localisebot::Error) -> String {
        self.refused.borrow_mut().take().unwrap_or_else(|| e.to_string())
    }
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
    let disk = Disk::default();
    io::load_mesh_with(&name, &bytes, &|uri| disk.get(&dir.join(uri)), limits()).map_err(|e| disk.explain(e))
}

/// Loads a scene file and everything it names; prints the loader's warnings on stderr.
pub fn load_scene_file(path: &Path) -> CliResult<Scene> {
    let text = read_text(path)?;
    let disk = Disk::default();
    let scene = load_scene_with(&path.to_string_lossy(), &text, &|p| disk.get(Path::new(p)), limits())
        .map_err(|e| disk.explain(e))?;
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
