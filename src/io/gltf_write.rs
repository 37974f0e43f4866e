//! A [`Mesh`] out as glTF 2.0: one node, one mesh, one `TRIANGLES` primitive with
//! `POSITION` (f32, with the `min`/`max` the specification requires) and `u32`
//! indices, in one buffer. [`glb`] writes a binary `.glb` (the buffer in its BIN
//! chunk); [`gltf_and_bin`] writes `.gltf` JSON text naming an external `.bin`.
//! The document is built with the `gltf` crate's `gltf::json` types, so what it writes
//! is what [`super::gltf`] reads back (tested by round trip). Positions lose what f32
//! cannot hold (about 1e-7 relative).

use crate::error::{Error, Result};
use crate::mesh::Mesh;
use gltf::json;
use json::validation::Checked::Valid;
use json::validation::USize64;
use std::borrow::Cow;

const GENERATOR: &str = concat!("localisebot ", env!("CARGO_PKG_VERSION"));

/// The document and its buffer's bytes (positions, then indices; 4-byte aligned).
/// `uri`: the buffer's external file, or `None` for a GLB's BIN chunk.
fn document(mesh: &Mesh, file: &str, uri: Option<&str>) -> Result<(json::Root, Vec<u8>)> {
    mesh.validate(file)?;
    let bounds = mesh.bounds().expect("a validated mesh has vertices");
    let mut bin = Vec::with_capacity(12 * mesh.positions.len() + 12 * mesh.triangles.len());
    for p in &mesh.positions {
        for c in p.to_array() {
            bin.extend_from_slice(&(c as f32).to_le_bytes());
        }
    }
    let positions_len = bin.len();
    for t in &mesh.triangles {
        for i in t {
            bin.extend_from_slice(&i.to_le_bytes());
        }
    }
    let indices_len = bin.len() - positions_len;

    let mut root = json::Root::default();
    root.asset.generator = Some(GENERATOR.into());
    let buffer = root.push(json::Buffer {
        byte_length: USize64::from(bin.len()),
        name: None,
        uri: uri.map(str::to_string),
        extensions: None,
        extras: Default::default(),
    });
    let view = |root: &mut json::Root, offset: usize, length: usize, target| {
        root.push(json::buffer::View {
            buffer,
            byte_length: USize64::from(length),
            byte_offset: Some(USize64::from(offset)),
            byte_stride: None,
            name: None,
            target: Some(Valid(target)),
            extensions: None,
            extras: Default::default(),
        })
    };
    let positions_view = view(&mut root, 0, positions_len, json::buffer::Target::ArrayBuffer);
    let indices_view = view(
        &mut root,
        positions_len,
        indices_len,
        json::buffer::Target::ElementArrayBuffer,
    );
    let accessor = |view, count: usize, component, type_, min_max: Option<[[f32; 3]; 2]>| json::Accessor {
        buffer_view: Some(view),
        byte_offset: Some(USize64(0)),
        count: USize64::from(count),
        component_type: Valid(json::accessor::GenericComponentType(component)),
        type_: Valid(type_),
        min: min_max.map(|[lo, _]| json::Value::from(lo.to_vec())),
        max: min_max.map(|[_, hi]| json::Value::from(hi.to_vec())),
        name: None,
        normalized: false,
        sparse: None,
        extensions: None,
        extras: Default::default(),
    };
    let f32s = |v: glam::DVec3| v.to_array().map(|c| c as f32);
    let positions = root.push(accessor(
        positions_view,
        mesh.positions.len(),
        json::accessor::ComponentType::F32,
        json::accessor::Type::Vec3,
        Some([f32s(bounds.min), f32s(bounds.max)]),
    ));
    let indices = root.push(accessor(
        indices_view,
        3 * mesh.triangles.len(),
        json::accessor::ComponentType::U32,
        json::accessor::Type::Scalar,
        None,
    ));
    let primitive = json::mesh::Primitive {
        attributes: [(Valid(json::mesh::Semantic::Positions), positions)].into(),
        indices: Some(indices),
        material: None,
        mode: Valid(json::mesh::Mode::Triangles),
        targets: None,
        extensions: None,
        extras: Default::default(),
    };
    let name = file.rsplit(['/', '\\']).next().unwrap_or(file);
    let stem = name.rsplit_once('.').map_or(name, |(s, _)| s).to_string();
    let gltf_mesh = root.push(json::Mesh {
        name: Some(stem.clone()),
        primitives: vec![primitive],
        weights: None,
        extensions: None,
        extras: Default::default(),
    });
    let node = root.push(json::Node {
        mesh: Some(gltf_mesh),
        name: Some(stem),
        ..Default::default()
    });
    let scene = root.push(json::Scene {
        name: None,
        nodes: vec![node],
        extensions: None,
        extras: Default::default(),
    });
    root.scene = Some(scene);
    Ok((root, bin))
}

fn too_big(file: &str, e: impl std::fmt::Display) -> Error {
    Error::Mesh {
        file: file.into(),
        problem: format!("cannot be written as glTF: {e}"),
    }
}

/// The mesh as a binary glTF (`.glb`) file. `file` names the mesh (its stem becomes
/// the glTF mesh's and node's name) and appears in errors: an invalid mesh (see
/// [`Mesh::validate`]) or one beyond GLB's 4 GiB.
pub fn glb(mesh: &Mesh, file: &str) -> Result<Vec<u8>> {
    let (root, bin) = document(mesh, file, None)?;
    let text = json::serialize::to_vec(&root).map_err(|e| too_big(file, e))?;
    let length = 12 + 8 + text.len().next_multiple_of(4) + 8 + bin.len();
    let glb = gltf::binary::Glb {
        header: gltf::binary::Header {
            magic: *b"glTF",
            version: 2,
            length: u32::try_from(length).map_err(|e| too_big(file, e))?,
        },
        json: Cow::Owned(text),
        bin: Some(Cow::Owned(bin)),
    };
    glb.to_vec().map_err(|e| too_big(file, e))
}

/// The mesh as glTF JSON text naming its buffer `bin_uri` (relative to the `.gltf`),
/// and that buffer's bytes. Errors as [`glb`].
pub fn gltf_and_bin(mesh: &Mesh, file: &str, bin_uri: &str) -> Result<(String, Vec<u8>)> {
    let (root, bin) = document(mesh, file, Some(bin_uri))?;
    let text = json::serialize::to_string_pretty(&root).map_err(|e| too_big(file, e))?;
    Ok((text + "\n", bin))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::app::shapes::{blob_mesh, toy_plane};
    use crate::io::{load_mesh, no_files};

    fn assert_same(a: &Mesh, b: &Mesh) {
        assert_eq!(a.triangles, b.triangles);
        assert_eq!(a.positions.len(), b.positions.len());
        for (p, q) in a.positions.iter().zip(&b.positions) {
            // f32 on the wire: relative 6e-8 of coordinates below 1.
            assert!(
                (*p - *q).abs().max_element() <= 1e-7 * (1.0 + p.abs().max_element()),
                "{p} vs {q}"
            );
        }
    }

    #[test]
    fn a_glb_reads_back_as_the_same_mesh() {
        for mesh in [toy_plane(), blob_mesh(7, 9)] {
            let bytes = glb(&mesh, "out/toy.glb").unwrap();
            assert_eq!(&bytes[..4], b"glTF");
            assert_eq!(
                u32::from_le_bytes(bytes[8..12].try_into().unwrap()) as usize,
                bytes.len()
            );
            assert_eq!(bytes.len() % 4, 0);
            assert_same(&mesh, &load_mesh("toy.glb", &bytes, &no_files).unwrap());
        }
    }

    #[test]
    fn a_gltf_with_its_bin_reads_back_as_the_same_mesh() {
        let mesh = toy_plane();
        let (text, bin) = gltf_and_bin(&mesh, "toy.gltf", "toy.bin").unwrap();
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(v["buffers"][0]["uri"], "toy.bin");
        assert_eq!(v["meshes"][0]["name"], "toy");
        assert_eq!(v["asset"]["version"], "2.0");
        let resolve = |uri: &str| (uri == "toy.bin").then(|| bin.clone());
        assert_same(&mesh, &load_mesh("toy.gltf", text.as_bytes(), &resolve).unwrap());
        // The buffer is needed: without it the loader names it.
        let e = load_mesh("toy.gltf", text.as_bytes(), &no_files).unwrap_err();
        assert!(e.to_string().contains("toy.bin"), "{e}");
    }

    #[test]
    fn the_bounds_are_written_and_an_invalid_mesh_is_refused() {
        let mesh = toy_plane();
        let (text, _) = gltf_and_bin(&mesh, "toy.gltf", "toy.bin").unwrap();
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        let b = mesh.bounds().unwrap();
        let min: [f64; 3] = serde_json::from_value(v["accessors"][0]["min"].clone()).unwrap();
        let max: [f64; 3] = serde_json::from_value(v["accessors"][0]["max"].clone()).unwrap();
        for k in 0..3 {
            assert!((min[k] - b.min[k]).abs() < 1e-7 && (max[k] - b.max[k]).abs() < 1e-7);
        }
        let empty = Mesh::default();
        let e = glb(&empty, "empty.glb").unwrap_err();
        assert!(e.to_string().contains("empty.glb"), "{e}");
    }
}
