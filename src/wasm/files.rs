//! Files as JavaScript hands them over — paths (folder-relative, or bare names) and
//! bytes — and how a scene's entries find theirs: by path, then by path suffix, then
//! ignoring case; same-named masks and images told apart by their pixels.

use crate::error::{Error, Result};
use crate::io::mask::decode_image;
use crate::io::scene::{scene_from_parts, Scene, SceneJson};
use crate::io::{join, load_mesh, parent_dir};
use wasm_bindgen::prelude::*;

/// What a file is wanted for; breaks ties between files of the same name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FileRole {
    /// A mask: among same-named files, the one whose pixels are only black and white.
    Mask,
    /// An image: among same-named files, the one that is not black and white.
    Image,
    /// Anything else (a mesh, a buffer): same-named files are an error.
    Other,
}

/// A set of named files (paths as dropped: folder-relative, or bare names).
#[wasm_bindgen]
#[derive(Debug, Default, Clone)]
pub struct FileSet {
    files: Vec<(String, Vec<u8>)>,
}

/// A path with `\` as `/`, `.` and `..` resolved, no leading `/`.
fn normalise(path: &str) -> String {
    join("", path).trim_start_matches('/').to_string()
}

/// Whether an image's pixels are all pure black or pure white grey (a mask).
fn black_and_white(bytes: &[u8]) -> bool {
    decode_image(bytes, "", "").is_ok_and(|img| {
        img.data
            .chunks_exact(4)
            .all(|p| p[0] == p[1] && p[1] == p[2] && (p[0] == 0 || p[0] == 255))
    })
}

#[wasm_bindgen]
impl FileSet {
    /// An empty set.
    #[wasm_bindgen(constructor)]
    pub fn new() -> FileSet {
        FileSet::default()
    }

    /// Adds a file. Several files may share a path (a file chooser gives bare names,
    /// so `images/a.png` and `masks/a.png` both arrive as `a.png`); an exact duplicate
    /// (same path, same bytes) is ignored.
    pub fn add(&mut self, path: &str, bytes: Vec<u8>) {
        let path = normalise(path);
        if !self.files.iter().any(|(p, b)| *p == path && *b == bytes) {
            self.files.push((path, bytes));
        }
    }

    /// The number of files.
    #[wasm_bindgen(getter)]
    pub fn length(&self) -> usize {
        self.files.len()
    }

    /// The files' paths, normalised (`/` separators, no `./`).
    pub fn names(&self) -> Vec<String> {
        self.files.iter().map(|(p, _)| p.clone()).collect()
    }
}

impl FileSet {
    /// Loads a mesh file's bytes; a `.gltf`'s buffers are taken from this set, by
    /// their URI joined onto the mesh's folder (then by name, like every lookup here).
    pub fn load_mesh(&self, file_name: &str, bytes: &[u8]) -> Result<crate::mesh::Mesh> {
        let dir = parent_dir(file_name);
        let resolve = |uri: &str| {
            self.find(&join(dir, uri), FileRole::Other)
                .ok()
                .flatten()
                .map(<[u8]>::to_vec)
        };
        load_mesh(file_name, bytes, &resolve)
    }

    /// The file a scene asks for as `wanted`: the file of that exact path; else the
    /// one whose path ends with it, or it with the file's (`masks/a.png` is served by
    /// `scene/masks/a.png` or by a bare `a.png`, never by `images/a.png`); else the
    /// same ignoring case. Several files at the first level that matches are told
    /// apart by `role`; `Err` names them when that fails. `Ok(None)`: no such file.
    pub fn find(&self, wanted: &str, role: FileRole) -> std::result::Result<Option<&[u8]>, String> {
        Ok(self.find_entry(wanted, role)?.map(|(_, bytes)| bytes.as_slice()))
    }

    /// As [`find`](Self::find), the matching (path, bytes) entry.
    fn find_entry(&self, wanted: &str, role: FileRole) -> std::result::Result<Option<&(String, Vec<u8>)>, String> {
        let w = normalise(wanted);
        let suffix = |a: &str, b: &str| a.len() > b.len() && a.ends_with(b) && a[..a.len() - b.len()].ends_with('/');
        let (wl, lower) = (w.to_ascii_lowercase(), |f: &str| f.to_ascii_lowercase());
        let exact = |f: &str| f == w;
        let by_suffix = |f: &str| suffix(f, &w) || suffix(&w, f);
        let any_case = |f: &str| suffix(&lower(f), &wl) || suffix(&wl, &lower(f)) || lower(f) == wl;
        let levels: [&dyn Fn(&str) -> bool; 3] = [&exact, &by_suffix, &any_case];
        for matches in levels {
            let hits: Vec<&(String, Vec<u8>)> = self.files.iter().filter(|(p, _)| matches(p)).collect();
            if hits.len() == 1 {
                return Ok(Some(hits[0]));
            }
            if hits.len() > 1 {
                let keep: Vec<_> = match role {
                    FileRole::Mask => hits.iter().filter(|f| black_and_white(&f.1)).collect(),
                    FileRole::Image => hits.iter().filter(|f| !black_and_white(&f.1)).collect(),
                    FileRole::Other => vec![],
                };
                if keep.len() == 1 {
                    return Ok(Some(keep[0]));
                }
                let names: Vec<&str> = hits.iter().map(|f| f.0.as_str()).collect();
                return Err(format!(
                    "ambiguous: {} files could be it ({}); give the files in their folders \
                     (drop the folder) so that their paths tell them apart",
                    hits.len(),
                    names.join(", ")
                ));
            }
        }
        Ok(None)
    }

    /// The scene `scene_file` (JSON `text`) with the mesh, masks and images it names
    /// taken from this set (paths joined onto the scene file's folder, then
    /// [`find`](Self::find), as a mask or an image), and warnings: an image not in
    /// the set (or only as the view's mask) is left out, for images are only shown.
    pub fn load_scene(&self, scene_file: &str, text: &str) -> Result<(Scene, Vec<String>)> {
        let mut json = SceneJson::parse(text, scene_file)?;
        let dir = parent_dir(scene_file);
        let missing = |path: String| Error::MissingFile {
            file: path,
            referrer: scene_file.into(),
        };
        // Every mask and image found first, by role; `fetch` then serves them by the
        // path written in the scene (an image written as its mask's path gets "#image").
        let mut found: Vec<(String, &[u8])> = Vec::new();
        let mut warnings = Vec::new();
        for v in &mut json.views {
            let mask = self
                .find_entry(&join(dir, &v.mask), FileRole::Mask)
                .map_err(|problem| Error::Mask {
                    view: v.name.clone(),
                    file: v.mask.clone(),
                    problem,
                })?
                .ok_or_else(|| missing(join(dir, &v.mask)))?;
            found.push((v.mask.clone(), &mask.1));
            let Some(image) = v.image.take() else { continue };
            match self.find_entry(&join(dir, &image), FileRole::Image) {
                Ok(Some(entry)) if !std::ptr::eq(entry, mask) => {
                    let key = if image == v.mask {
                        format!("{image}#image")
                    } else {
                        image
                    };
                    found.push((key.clone(), &entry.1));
                    v.image = Some(key);
                }
                Ok(_) => warnings.push(format!(
                    "view '{}': image '{image}' not given: showing the mask",
                    v.name
                )),
                Err(problem) => {
                    return Err(Error::Image {
                        view: v.name.clone(),
                        file: image,
                        problem,
                    })
                }
            }
        }
        let mesh_path = join(dir, &json.mesh);
        let mesh_bytes = self
            .find(&mesh_path, FileRole::Other)
            .map_err(|problem| Error::Mesh {
                file: mesh_path.clone(),
                problem,
            })?
            .ok_or_else(|| missing(mesh_path.clone()))?;
        let mesh_dir = parent_dir(&mesh_path);
        let extra = |uri: &str| {
            self.find(&join(mesh_dir, uri), FileRole::Other)
                .ok()
                .flatten()
                .map(<[u8]>::to_vec)
        };
        let mesh = load_mesh(&mesh_path, mesh_bytes, &extra)?;
        let fetch = |rel: &str| -> Result<Vec<u8>> {
            let bytes = found.iter().find(|(p, _)| p == rel).map(|(_, b)| b.to_vec());
            bytes.ok_or_else(|| missing(join(dir, rel)))
        };
        Ok((scene_from_parts(scene_file, json, mesh, &fetch)?, warnings))
    }
}

/// Checks a mesh file; returns its triangle count. `extra` supplies a `.gltf`'s buffers.
#[wasm_bindgen(js_name = checkMesh)]
pub fn check_mesh(file_name: &str, bytes: &[u8], extra: &FileSet) -> Result<usize, JsError> {
    Ok(extra.load_mesh(file_name, bytes)?.triangles.len())
}
