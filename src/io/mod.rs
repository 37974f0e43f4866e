//! Bytes in, core types out (and back): meshes (glTF, OBJ, PLY; glTF and PLY written), masks and images (PNG),
//! scene files (SPEC §3) and the grasps they list. Nothing here touches the file system: files the data
//! refers to are asked for through a resolver closure, `&dyn Fn(&str) -> Option<Vec<u8>>`,
//! given the path as written relative to the scene (or mesh) file.

pub mod bop;
pub mod fileset;
pub mod gltf;
pub mod gltf_write;
pub mod grasp;
pub mod mask;
pub mod nerf;
pub mod obj;
pub mod ply;
pub mod png;
pub mod scene;

use crate::error::{Error, Result};
use crate::limits::Limits;
use crate::mesh::Mesh;

/// A resolver: the bytes of a file named relative to the referring file, if supplied.
pub type Resolver<'a> = &'a dyn Fn(&str) -> Option<Vec<u8>>;

/// A resolver that knows no files.
pub fn no_files(_: &str) -> Option<Vec<u8>> {
    None
}

/// The folder part of a `/`-separated path ("" for a bare name).
pub fn parent_dir(path: &str) -> &str {
    match path.rfind(['/', '\\']) {
        Some(i) => &path[..i],
        None => "",
    }
}

/// Joins a relative path onto a folder, resolving `./` and `../` lexically.
pub fn join(dir: &str, rel: &str) -> String {
    let mut parts: Vec<&str> = dir.split(['/', '\\']).filter(|s| !s.is_empty() && *s != ".").collect();
    if rel.starts_with('/') {
        parts.clear();
    }
    for p in rel.split(['/', '\\']) {
        match p {
            "" | "." => {}
            ".." => {
                if parts.last().is_some_and(|l| *l != "..") {
                    parts.pop();
                } else {
                    parts.push("..");
                }
            }
            p => parts.push(p),
        }
    }
    let s = parts.join("/");
    if dir.starts_with('/') || rel.starts_with('/') {
        format!("/{s}")
    } else {
        s
    }
}

/// Loads a mesh from its bytes, choosing the format by content (GLB magic, JSON, `ply`
/// magic) or extension (`.obj`, `.ply`). `extra` supplies files the mesh refers to (a `.gltf`'s `.bin`
/// buffers), by URI relative to the mesh file.
pub fn load_mesh(file: &str, bytes: &[u8], extra: Resolver) -> Result<Mesh> {
    load_mesh_with(file, bytes, extra, &Limits::DEFAULT)
}

/// As [`load_mesh`], the file's size and declared counts checked against `limits`
/// before anything is allocated for them.
pub fn load_mesh_with(file: &str, bytes: &[u8], extra: Resolver, limits: &Limits) -> Result<Mesh> {
    limits.check_file(file, bytes.len() as u64)?;
    let lower = file.to_ascii_lowercase();
    let mesh = if bytes.starts_with(b"glTF") || lower.ends_with(".glb") || lower.ends_with(".gltf") {
        gltf::load_with(file, bytes, extra, limits)?
    } else if lower.ends_with(".obj") {
        obj::load_with(file, bytes, limits)?
    } else if lower.ends_with(".ply") || bytes.starts_with(b"ply\n") || bytes.starts_with(b"ply\r\n") {
        ply::load_with(file, bytes, limits)?
    } else {
        let head = bytes.iter().find(|b| !b.is_ascii_whitespace());
        if head == Some(&b'{') {
            gltf::load_with(file, bytes, extra, limits)?
        } else {
            return Err(Error::Mesh {
                file: file.into(),
                problem: "unknown mesh format: expected .glb, .gltf, .obj or .ply".into(),
            });
        }
    };
    mesh.validate(file)?;
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn join_paths() {
        assert_eq!(join("a/b", "c.bin"), "a/b/c.bin");
        assert_eq!(join("a/b", "../c.bin"), "a/c.bin");
        assert_eq!(join("", "./masks/x.png"), "masks/x.png");
        assert_eq!(join("/x/y", "z"), "/x/y/z");
        assert_eq!(parent_dir("a/b/c.gltf"), "a/b");
        assert_eq!(parent_dir("c.gltf"), "");
    }

    #[test]
    fn unknown_format_is_named() {
        let e = load_mesh("model.stl", b"solid x", &no_files).unwrap_err();
        assert!(e.to_string().contains("model.stl") && e.to_string().contains("unknown mesh format"));
    }
}
