//! [`FileSet`]: files as JavaScript hands them over (paths and bytes), a thin wrapper
//! of [`crate::io::fileset::FileSet`], which holds the matching policy (which file is
//! the scene, the mesh, each view's mask and image; lookups by path, then by name,
//! same-named masks and images told apart by their pixels). Also the lists of files a
//! scene or a glTF names, for the page's example fetcher.

use crate::error::Result;
use crate::io::fileset;
pub use crate::io::fileset::{FileRole, Plan};
use crate::io::scene::Scene;
use wasm_bindgen::prelude::*;

/// A set of named files (paths as dropped: folder-relative, or bare names).
#[wasm_bindgen]
#[derive(Debug, Default, Clone)]
pub struct FileSet(fileset::FileSet);

#[wasm_bindgen]
impl FileSet {
    /// An empty set.
    #[wasm_bindgen(constructor)]
    pub fn new() -> FileSet {
        FileSet::default()
    }

    /// Adds a file. Several files may share a path (a file chooser gives bare names,
    /// so `images/a.png` and `masks/a.png` both arrive as `a.png`); an exact duplicate
    /// (same path, same bytes) is ignored. A file over the `file_bytes` limit is
    /// refused before it is copied into the module's memory.
    pub fn add(&mut self, path: &str, bytes: &js_sys::Uint8Array) -> Result<(), JsError> {
        self.0.limits().check_file(path, bytes.length() as u64)?;
        self.0.add(path, bytes.to_vec());
        Ok(())
    }

    /// Sets an input limit of this set's loads (see README, "Limits"): `file_bytes`,
    /// `view_pixels`, `total_pixels`, `views`, `vertices` or `triangles`; a whole
    /// number of at least 1.
    #[wasm_bindgen(js_name = setLimit)]
    pub fn set_limit(&mut self, name: &str, value: f64) -> Result<(), JsError> {
        let mut l = *self.0.limits();
        l.set(name, whole(name, value)?)?;
        self.0.set_limits(l);
        Ok(())
    }

    /// Whether later loads leave out the images of views that have masks (default
    /// `false`): a pool Worker computes with the masks alone, and an image costs four
    /// times its mask's memory.
    #[wasm_bindgen(js_name = setMasksOnly)]
    pub fn set_masks_only(&mut self, on: bool) {
        self.0.set_masks_only(on);
    }

    /// The limits as an object of numbers, keyed as `setLimit` names them.
    #[wasm_bindgen(getter)]
    pub fn limits(&self) -> JsValue {
        let l = self.0.limits();
        let o = js_sys::Object::new();
        for (name, v) in [
            ("file_bytes", l.file_bytes),
            ("view_pixels", l.view_pixels),
            ("total_pixels", l.total_pixels),
            ("views", l.views),
            ("vertices", l.vertices),
            ("triangles", l.triangles),
        ] {
            let _ = js_sys::Reflect::set(&o, &name.into(), &(v as f64).into());
        }
        o.into()
    }

    /// Whether the scene these files make has views without a mask — photographs to
    /// segment (a `PhotoSession`, and the segmenter's module) rather than a `Session`.
    /// Decided from the scene's JSON alone; `false` when the files make no scene.
    #[wasm_bindgen(js_name = needsSegmenter)]
    pub fn needs_segmenter(&self) -> bool {
        self.0.needs_segmenter()
    }

    /// The number of files.
    #[wasm_bindgen(getter)]
    pub fn length(&self) -> usize {
        self.0.len()
    }

    /// The files' paths, normalised (`/` separators, no `./`).
    pub fn names(&self) -> Vec<String> {
        self.0.names()
    }
}

/// A limit's value from JavaScript: a whole number from 1 to 2⁵³.
pub(crate) fn whole(name: &str, value: f64) -> Result<u64, JsError> {
    if value.fract() != 0.0 || !(1.0..=9_007_199_254_740_992.0).contains(&value) {
        return Err(JsError::new(&format!(
            "limit {name}: {value} is not a whole number from 1 to 2^53"
        )));
    }
    Ok(value as u64)
}

impl FileSet {
    /// Adds a file's bytes (for Rust callers; JavaScript calls [`FileSet::add`]).
    pub fn add_bytes(&mut self, path: &str, bytes: Vec<u8>) {
        self.0.add(path, bytes);
    }

    /// Sets the limits of later loads.
    pub fn set_limits(&mut self, limits: crate::limits::Limits) {
        self.0.set_limits(limits);
    }

    /// The core file set.
    pub fn inner(&self) -> &fileset::FileSet {
        &self.0
    }

    /// See [`fileset::FileSet::load_mesh`].
    pub fn load_mesh(&self, file_name: &str, bytes: &[u8]) -> Result<crate::mesh::Mesh> {
        self.0.load_mesh(file_name, bytes)
    }

    /// See [`fileset::FileSet::find`].
    pub fn find(&self, wanted: &str, role: FileRole) -> std::result::Result<Option<&[u8]>, String> {
        self.0.find(wanted, role)
    }

    /// See [`fileset::FileSet::load_scene`].
    pub fn load_scene(&self, scene_file: &str, text: &str) -> Result<(Scene, Vec<String>)> {
        self.0.load_scene(scene_file, text)
    }

    /// See [`fileset::FileSet::plan`].
    pub fn plan(&self) -> Result<Plan> {
        self.0.plan()
    }
}

/// Checks a mesh file; returns its triangle count. `extra` supplies a `.gltf`'s buffers.
#[wasm_bindgen(js_name = checkMesh)]
pub fn check_mesh(file_name: &str, bytes: &[u8], extra: &FileSet) -> Result<usize, JsError> {
    Ok(extra.load_mesh(file_name, bytes)?.triangles.len())
}

/// The files a scene file names (mesh, masks, images, ignore masks), joined onto its
/// folder: what to fetch to load it.
#[wasm_bindgen(js_name = sceneFiles)]
pub fn scene_files(scene_file: &str, text: &str) -> Result<Vec<String>, JsError> {
    Ok(fileset::scene_references(scene_file, text)?)
}

/// The external files a mesh file refers to (a glTF's `.bin` buffers), joined onto its folder.
#[wasm_bindgen(js_name = meshFiles)]
pub fn mesh_files(mesh_file: &str, bytes: &[u8]) -> Vec<String> {
    fileset::mesh_references(mesh_file, bytes)
}
