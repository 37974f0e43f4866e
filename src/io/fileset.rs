//! Files as a user hands them over — dropped or chosen in a browser, paths
//! folder-relative or bare names, and bytes — and the policy that makes one scene of
//! them. [`FileSet::plan`] decides which file is what:
//!
//! - a `scene.json` (a JSON object with a `mesh` string and a `views` array) is the
//!   scene; the files it names are found by path relative to it, then by path suffix,
//!   then ignoring case ([`FileSet::find`]); a mesh dropped under another name is used
//!   when it is the only one;
//! - else one camera JSON per view (a camera, or a scene view entry with `camera` and
//!   optionally `name`, `mask`, `image`): `NAME.json` is the view `NAME`, its mask
//!   `masks/NAME.png`, `NAME_mask.png`, `mask_NAME.png` or a lone `NAME.png`, its image
//!   `images/NAME.png`, `rgb/NAME.png` or `NAME_image.png` (or `.jpg`, `.jpeg`: a
//!   JPEG is always a photograph, and a lone `NAME.jpg` is the view's); two files both
//!   called `NAME.png` are told apart by their pixels (a mask is only black and white);
//! - a mesh alone (`.glb`, `.gltf` with its `.bin`, `.obj`, `.ply`) is checked and
//!   reported as lacking a scene.
//!
//! Everything here is plain Rust over bytes: the wasm binding (`wasm::FileSet`) only
//! wraps it, and the tests below run natively.

use crate::error::{Error, Result};
use crate::io::mask::decode_image;
use crate::io::scene::{scene_from_parts, Scene, SceneJson};
use crate::io::{join, load_mesh_with, parent_dir};
use crate::limits::Limits;
use crate::mesh::Mesh;
use serde_json::{json, Value};
use std::cmp::Ordering;

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

/// A set of named files (paths as given: folder-relative, or bare names).
#[derive(Debug, Default, Clone)]
pub struct FileSet {
    files: Vec<(String, Vec<u8>)>,
    limits: Limits,
    /// Leave out the images of views that have masks ([`FileSet::set_masks_only`]).
    masks_only: bool,
}

/// What [`FileSet::plan`] found the files to be.
#[derive(Debug, Clone, PartialEq)]
pub enum Plan {
    /// A scene: its file's path and JSON text (made up as `cameras.json` from
    /// per-view camera files), to load with [`FileSet::load_scene`].
    Scene {
        /// The scene file's path (files it names are relative to its folder).
        file: String,
        /// Its JSON text.
        text: String,
    },
    /// A mesh and no scene.
    MeshOnly {
        /// The mesh file's path.
        file: String,
    },
}

/// The mesh file types [`FileSet::load_mesh`] reads, by extension.
pub const MESH_EXTENSIONS: [&str; 4] = ["glb", "gltf", "obj", "ply"];

/// A path with `\` as `/`, `.` and `..` resolved, no leading `/`.
fn normalise(path: &str) -> String {
    join("", path).trim_start_matches('/').to_string()
}

fn base_name(path: &str) -> &str {
    path.rsplit(['/', '\\']).next().unwrap_or(path)
}

/// The extensions of the masks' and photographs' files (a mask is a PNG).
const PICTURE_EXTENSIONS: [&str; 3] = ["png", "jpg", "jpeg"];

fn extension(path: &str) -> String {
    base_name(path)
        .rsplit_once('.')
        .map(|(_, e)| e.to_ascii_lowercase())
        .unwrap_or_default()
}

fn stem(path: &str) -> &str {
    let b = base_name(path);
    b.rsplit_once('.').map_or(b, |(s, _)| s)
}

/// Whether a file name is a mesh's (`.glb`, `.gltf`, `.obj`, `.ply`).
pub fn is_mesh_file(path: &str) -> bool {
    MESH_EXTENSIONS.contains(&extension(path).as_str())
}

/// Whether an image's pixels are all pure black or pure white grey (a mask). An
/// image of more than `max_pixels` (by its header) is not decoded: it is not a mask
/// this set could load.
fn black_and_white(bytes: &[u8], max_pixels: u64) -> bool {
    let small = crate::io::mask::dimensions(bytes).is_ok_and(|(w, h)| w as u64 * h as u64 <= max_pixels);
    small
        && decode_image(bytes, "", "").is_ok_and(|img| {
            img.data
                .chunks_exact(4)
                .all(|p| p[0] == p[1] && p[1] == p[2] && (p[0] == 0 || p[0] == 255))
        })
}

/// Compares names as people number things: `view2` before `view10`, case ignored.
pub fn natural_cmp(a: &str, b: &str) -> Ordering {
    fn chunks(s: &str) -> Vec<(bool, String)> {
        let mut out: Vec<(bool, String)> = Vec::new();
        for c in s.chars() {
            let digit = c.is_ascii_digit();
            match out.last_mut() {
                Some((d, text)) if *d == digit => text.push(c),
                _ => out.push((digit, c.to_string())),
            }
        }
        out
    }
    let (x, y) = (chunks(a), chunks(b));
    for ((dx, tx), (dy, ty)) in x.iter().zip(&y) {
        let o = match (dx, dy) {
            (true, true) => {
                let (nx, ny) = (tx.trim_start_matches('0'), ty.trim_start_matches('0'));
                nx.len().cmp(&ny.len()).then_with(|| nx.cmp(ny))
            }
            _ => tx.to_lowercase().cmp(&ty.to_lowercase()),
        };
        if o != Ordering::Equal {
            return o;
        }
    }
    x.len().cmp(&y.len()).then_with(|| a.cmp(b))
}

/// A JSON file of the set, parsed.
struct JsonFile<'a> {
    path: &'a str,
    text: &'a str,
    value: Value,
}

/// The set's files sorted by what they are.
#[derive(Default)]
struct Classified<'a> {
    meshes: Vec<&'a str>,
    /// PNG and JPEG files.
    pictures: Vec<&'a str>,
    scenes: Vec<JsonFile<'a>>,
    cameras: Vec<JsonFile<'a>>,
}

/// The mask and image of the view `name` among `pictures`, by the naming habits of the
/// module doc. A mask and an image both written `NAME.png` mean "the two files of that
/// name": [`FileSet::load_scene`] tells them apart by content.
fn match_view(name: &str, pictures: &[&str]) -> (Option<String>, Option<String>) {
    let n = name.to_lowercase();
    let parts = |p: &str| {
        let l = p.to_lowercase();
        let mut it = l.rsplit('/');
        let base = it.next().unwrap_or_default().to_string();
        (it.next().unwrap_or_default().to_string(), base)
    };
    let is_mask = |p: &str| {
        let (dir, base) = parts(p);
        (matches!(dir.as_str(), "mask" | "masks") && base == format!("{n}.png"))
            || ['.', '_', '-']
                .iter()
                .any(|c| base == format!("{n}{c}mask.png") || base == format!("mask{c}{n}.png"))
    };
    let is_image = |p: &str| {
        let (dir, base) = parts(p);
        PICTURE_EXTENSIONS.iter().any(|ext| {
            (matches!(dir.as_str(), "image" | "images" | "rgb") && base == format!("{n}.{ext}"))
                || ['.', '_', '-'].iter().any(|c| {
                    ["image", "rgb", "color", "colour"]
                        .iter()
                        .any(|w| base == format!("{n}{c}{w}.{ext}"))
                })
        })
    };
    let mask = pictures.iter().find(|p| is_mask(p)).map(|p| p.to_string());
    // A lone `NAME.jpg` (a JPEG is never a mask here) is the photograph.
    let lone_jpeg = || {
        pictures
            .iter()
            .find(|p| {
                ["jpg", "jpeg"]
                    .iter()
                    .any(|ext| base_name(p).to_lowercase() == format!("{n}.{ext}"))
            })
            .map(|p| p.to_string())
    };
    let image = pictures
        .iter()
        .find(|p| is_image(p))
        .map(|p| p.to_string())
        .or_else(lone_jpeg);
    let plain: Vec<&str> = pictures
        .iter()
        .copied()
        .filter(|p| base_name(p).to_lowercase() == format!("{n}.png"))
        .collect();
    if let Some(mask) = mask {
        let image = image.or_else(|| (plain.len() == 1 && plain[0] != mask).then(|| plain[0].to_string()));
        return (Some(mask), image);
    }
    if plain.is_empty() {
        return (None, image);
    }
    if let Some(image) = image {
        let mask = plain.iter().find(|p| **p != image).map(|p| p.to_string());
        return (mask, Some(image));
    }
    if plain.len() == 1 {
        (Some(plain[0].to_string()), None)
    } else {
        (Some(format!("{name}.png")), Some(format!("{name}.png")))
    }
}

impl FileSet {
    /// An empty set.
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

    /// The limits loads from this set are checked against (default [`Limits::DEFAULT`]).
    pub fn limits(&self) -> &Limits {
        &self.limits
    }

    /// Sets the limits of later loads.
    pub fn set_limits(&mut self, limits: Limits) {
        self.limits = limits;
    }

    /// Whether later loads leave out the images of views that have masks (default
    /// `false`): what computes the fit without showing it (a page's pool Worker) needs
    /// only the masks, and an image decoded costs four times its mask's memory. A view
    /// without a mask still has its photograph.
    pub fn set_masks_only(&mut self, on: bool) {
        self.masks_only = on;
    }

    /// The number of files.
    pub fn len(&self) -> usize {
        self.files.len()
    }

    /// Whether the set holds no file.
    pub fn is_empty(&self) -> bool {
        self.files.is_empty()
    }

    /// The files' paths, normalised (`/` separators, no `./`), in the order added.
    pub fn names(&self) -> Vec<String> {
        self.files.iter().map(|(p, _)| p.clone()).collect()
    }

    /// Loads a mesh file's bytes; a `.gltf`'s buffers are taken from this set, by
    /// their URI joined onto the mesh's folder (then by name, like every lookup here).
    pub fn load_mesh(&self, file_name: &str, bytes: &[u8]) -> Result<Mesh> {
        let dir = parent_dir(file_name);
        let resolve = |uri: &str| {
            self.find(&join(dir, uri), FileRole::Other)
                .ok()
                .flatten()
                .map(<[u8]>::to_vec)
        };
        load_mesh_with(file_name, bytes, &resolve, &self.limits)
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
                    FileRole::Mask => hits
                        .iter()
                        .filter(|f| black_and_white(&f.1, self.limits.view_pixels))
                        .collect(),
                    FileRole::Image => hits
                        .iter()
                        .filter(|f| !black_and_white(&f.1, self.limits.view_pixels))
                        .collect(),
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

    /// Sorts the files: meshes, pictures (PNG, JPEG), scene files, camera files (others ignored).
    fn classify(&self) -> Result<Classified<'_>> {
        let mut out = Classified::default();
        for (path, bytes) in &self.files {
            let ext = extension(path);
            if is_mesh_file(path) {
                out.meshes.push(path);
            } else if PICTURE_EXTENSIONS.contains(&ext.as_str()) {
                out.pictures.push(path);
            } else if ext == "json" {
                let bad = |problem: String| Error::Json {
                    file: path.clone(),
                    problem,
                };
                self.limits.check_file(path, bytes.len() as u64)?;
                let text = std::str::from_utf8(bytes).map_err(|_| bad("not UTF-8 text".into()))?;
                crate::limits::check_json_depth(path, bytes)?;
                let value: Value = serde_json::from_str(text).map_err(|e| bad(format!("not valid JSON ({e})")))?;
                let file = JsonFile { path, text, value };
                let v = &file.value;
                if v.get("mesh").is_some_and(Value::is_string) && v.get("views").is_some_and(Value::is_array) {
                    out.scenes.push(file);
                } else if v.get("camera").is_some_and(|c| !c.is_null()) || v.get("fx").is_some() {
                    out.cameras.push(file);
                }
            }
        }
        Ok(out)
    }

    /// Which file is the scene (or the mesh, when there is no scene); see the module doc.
    /// Errors name the files: none given, several scene files, per-view cameras with no
    /// mesh or several, a view without a mask, nothing that makes a scene.
    pub fn plan(&self) -> Result<Plan> {
        let files = |e: String| Error::Files(e);
        if self.files.is_empty() {
            return Err(files("no files were given".into()));
        }
        let Classified {
            meshes,
            pictures,
            mut scenes,
            cameras,
        } = self.classify()?;
        if scenes.len() > 1 {
            let names: Vec<&str> = scenes.iter().map(|s| s.path).collect();
            return Err(files(format!(
                "several scene files ({}): give one scene at a time",
                names.join(", ")
            )));
        }
        if let Some(JsonFile { path, text, mut value }) = scenes.pop() {
            // A mesh dropped under another name than the scene's: use it when it is the only one.
            let wanted = value["mesh"].as_str().map(|m| base_name(m).to_lowercase());
            let named_is_here = |w: &str| self.files.iter().any(|(p, _)| base_name(p).to_lowercase() == w);
            if let (Some(w), [only]) = (wanted, meshes.as_slice()) {
                if !named_is_here(&w) {
                    value["mesh"] = Value::from(*only);
                    return Ok(Plan::Scene {
                        file: path.into(),
                        text: value.to_string(),
                    });
                }
            }
            return Ok(Plan::Scene {
                file: path.into(),
                text: text.into(),
            });
        }
        if !cameras.is_empty() {
            let mesh = match meshes.as_slice() {
                [one] => *one,
                [] => {
                    return Err(files(
                        "no mesh: add a .glb, .gltf (with its .bin), .obj or .ply file".into(),
                    ))
                }
                several => return Err(files(format!("several meshes ({}): choose one", several.join(", ")))),
            };
            let mut views = Vec::with_capacity(cameras.len());
            for JsonFile { path, value, .. } in &cameras {
                let name = value
                    .get("name")
                    .and_then(Value::as_str)
                    .map_or_else(|| stem(path).to_string(), str::to_string);
                let (mut found_mask, mut found_image) = match_view(&name, &pictures);
                // A lone `NAME.png` that is not black and white is the view's photograph.
                if let (Some(m), None) = (&found_mask, &found_image) {
                    let photo = self
                        .files
                        .iter()
                        .any(|(p, b)| p == m && !black_and_white(b, self.limits.view_pixels));
                    if photo {
                        found_image = found_mask.take();
                    }
                }
                let given = |k: &str| value.get(k).and_then(Value::as_str).map(str::to_string);
                let mask = given("mask").or(found_mask);
                let image = given("image").or(found_image);
                if mask.is_none() && image.is_none() {
                    return Err(files(format!(
                        "view '{name}' ({path}): no mask and no photograph: add {name}.png (a mask or the \
                         photograph), masks/{name}.png or images/{name}.png"
                    )));
                }
                let camera = value.get("camera").filter(|c| !c.is_null()).unwrap_or(value);
                let mut view = json!({ "name": name, "camera": camera });
                if let Some(mask) = mask {
                    view["mask"] = Value::from(mask);
                }
                if let Some(image) = image {
                    view["image"] = Value::from(image);
                }
                for key in ["box", "ignore"] {
                    if let Some(v) = value.get(key).filter(|v| !v.is_null()) {
                        view[key] = v.clone();
                    }
                }
                views.push(view);
            }
            views.sort_by(|a, b| natural_cmp(a["name"].as_str().unwrap(), b["name"].as_str().unwrap()));
            let scene = json!({ "version": 1, "mesh": mesh, "views": views });
            return Ok(Plan::Scene {
                file: "cameras.json".into(),
                text: scene.to_string(),
            });
        }
        if let Some(mesh) = meshes.first() {
            return Ok(Plan::MeshOnly { file: mesh.to_string() });
        }
        Err(files(format!(
            "no scene.json or camera .json among {}: give a scene.json (or one camera .json per view) \
             with the mesh, masks and images",
            self.names().join(", ")
        )))
    }

    /// Whether the scene the files make has views without a mask (photographs to
    /// segment), by its JSON alone: nothing is decoded. `false` when the files make no
    /// scene (loading them says why).
    pub fn needs_segmenter(&self) -> bool {
        match self.plan() {
            Ok(Plan::Scene { file, text }) => {
                SceneJson::parse(&text, &file).is_ok_and(|s| s.views.iter().any(|v| v.mask.is_none()))
            }
            _ => false,
        }
    }

    /// The scene the files make ([`plan`](Self::plan), then [`load_scene`](Self::load_scene)),
    /// with the scene file's path and the warnings. A mesh without a scene is loaded
    /// (its own errors come first), then reported as lacking the scene.
    pub fn load(&self) -> Result<(Scene, Vec<String>, String)> {
        match self.plan()? {
            Plan::Scene { file, text } => {
                let (scene, warnings) = self.load_scene(&file, &text)?;
                Ok((scene, warnings, file))
            }
            Plan::MeshOnly { file } => {
                let bytes = &self
                    .files
                    .iter()
                    .find(|(p, _)| *p == file)
                    .expect("planned from the set")
                    .1;
                let mesh = self.load_mesh(&file, bytes)?;
                Err(Error::Files(format!(
                    "{file}: a valid mesh ({} triangles), but there is no scene: add a scene.json \
                     (or one camera .json per view) and the masks",
                    mesh.triangles.len()
                )))
            }
        }
    }

    /// The scene `scene_file` (JSON `text`) with the mesh, masks and images it names
    /// taken from this set (paths joined onto the scene file's folder, then
    /// [`find`](Self::find), as a mask or an image), and warnings: an image not in
    /// the set (or only as the view's mask) is left out, for images are only shown.
    pub fn load_scene(&self, scene_file: &str, text: &str) -> Result<(Scene, Vec<String>)> {
        self.limits.check_file(scene_file, text.len() as u64)?;
        let mut json = SceneJson::parse(text, scene_file)?;
        self.limits.check_views(scene_file, json.views.len() as u64)?;
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
            let mask = match &v.mask {
                None => None,
                Some(file) => {
                    let entry = self
                        .find_entry(&join(dir, file), FileRole::Mask)
                        .map_err(|problem| Error::Mask {
                            view: v.name.clone(),
                            file: file.clone(),
                            problem,
                        })?
                        .ok_or_else(|| missing(join(dir, file)))?;
                    found.push((file.clone(), &entry.1));
                    Some(entry)
                }
            };
            if let Some(ignore) = &v.ignore {
                let entry = self
                    .find_entry(&join(dir, ignore), FileRole::Mask)
                    .map_err(|problem| Error::Mask {
                        view: v.name.clone(),
                        file: ignore.clone(),
                        problem,
                    })?
                    .ok_or_else(|| missing(join(dir, ignore)))?;
                found.push((ignore.clone(), &entry.1));
            }
            let Some(image) = v.image.take() else { continue };
            if self.masks_only && mask.is_some() {
                continue;
            }
            match self.find_entry(&join(dir, &image), FileRole::Image) {
                Ok(Some(entry)) if mask.is_none_or(|m| !std::ptr::eq(entry, m)) => {
                    let key = if v.mask.as_ref() == Some(&image) {
                        format!("{image}#image")
                    } else {
                        image
                    };
                    found.push((key.clone(), &entry.1));
                    v.image = Some(key);
                }
                // Without a mask the photograph is what the mask is made from.
                Ok(_) if mask.is_none() => return Err(missing(join(dir, &image))),
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
        let mesh = self.load_mesh(&mesh_path, mesh_bytes)?;
        let fetch = |rel: &str| -> Result<Vec<u8>> {
            let bytes = found.iter().find(|(p, _)| p == rel).map(|(_, b)| b.to_vec());
            bytes.ok_or_else(|| missing(join(dir, rel)))
        };
        let scene = scene_from_parts(scene_file, json, mesh, &fetch, &self.limits)?;
        warnings.extend(scene.warnings.iter().cloned());
        Ok((scene, warnings))
    }
}

/// The files a scene file names — its mesh, and each view's mask, image and ignore
/// mask — as paths joined onto the scene file's folder, each once, in that order: what
/// to fetch to load it. A mesh's own files (a `.gltf`'s buffers) are [`mesh_references`].
pub fn scene_references(scene_file: &str, text: &str) -> Result<Vec<String>> {
    let bad = |problem: String| Error::Json {
        file: scene_file.into(),
        problem,
    };
    let v: Value = serde_json::from_str(text).map_err(|e| bad(format!("not valid JSON ({e})")))?;
    let mesh = v["mesh"]
        .as_str()
        .ok_or_else(|| bad("no \"mesh\": expected the mesh file's path".into()))?;
    let views = v["views"]
        .as_array()
        .ok_or_else(|| bad("no \"views\": expected a list of views".into()))?;
    let dir = parent_dir(scene_file);
    let mut out = vec![join(dir, mesh)];
    for view in views {
        for key in ["mask", "image", "ignore"] {
            if let Some(p) = view[key].as_str() {
                let p = join(dir, p);
                if !out.contains(&p) {
                    out.push(p);
                }
            }
        }
    }
    Ok(out)
}

/// The external files a mesh file refers to (a glTF's buffers that are not data URIs),
/// as paths joined onto the mesh's folder; none for other formats or unreadable files
/// (loading the mesh then says what is wrong).
pub fn mesh_references(mesh_file: &str, bytes: &[u8]) -> Vec<String> {
    let json: Option<Value> = if bytes.starts_with(b"glTF") {
        // Through the loader's own header checks: the gltf crate's GLB reader
        // underflows on a header length below 12 (found by fuzzing).
        crate::io::gltf::split_glb(bytes)
            .ok()
            .and_then(|(json, _)| serde_json::from_slice(&json).ok())
    } else if extension(mesh_file) == "gltf" {
        serde_json::from_slice(bytes).ok()
    } else {
        None
    };
    let dir = parent_dir(mesh_file);
    json.as_ref()
        .and_then(|v| v["buffers"].as_array())
        .into_iter()
        .flatten()
        .filter_map(|b| b["uri"].as_str())
        .filter(|u| !u.starts_with("data:"))
        .map(|u| join(dir, u))
        .collect()
}

#[cfg(test)]
mod tests;
