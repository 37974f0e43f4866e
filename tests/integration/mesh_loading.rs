//! Mesh loading on the Khronos sample files of `../shared/data/gltf` (expected values
//! from `../shared/data/SOURCES.md`), malformed input, and one OBJ.

use crate::data;
use glam::DVec3;
use localisebot::io::{gltf, load_mesh, no_files};
use localisebot::{Error, Mesh};
use std::path::{Path, PathBuf};

fn read(p: &Path) -> Vec<u8> {
    std::fs::read(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// Loads a mesh of `../shared/data`, resolving external files beside it.
fn load(rel: &str) -> localisebot::Result<Mesh> {
    load_at(data(rel), rel)
}

/// Loads the mesh file at `path`, named `rel` in errors.
fn load_at(path: PathBuf, rel: &str) -> localisebot::Result<Mesh> {
    let dir: PathBuf = path.parent().unwrap().to_path_buf();
    load_mesh(rel, &read(&path), &move |uri| std::fs::read(dir.join(uri)).ok())
}

fn assert_bounds(m: &Mesh, min: [f64; 3], max: [f64; 3], tol: f64) {
    let b = m.bounds().unwrap();
    let (emin, emax) = (DVec3::from_array(min), DVec3::from_array(max));
    assert!(
        (b.min - emin).abs().max_element() <= tol && (b.max - emax).abs().max_element() <= tol,
        "bounds {:?}..{:?}, expected {emin:?}..{emax:?} (±{tol})",
        b.min,
        b.max
    );
}

#[test]
fn duck_glb_and_embedded_gltf_agree() {
    let glb = load("gltf/Duck/glTF-Binary/Duck.glb").unwrap();
    let emb = load("gltf/Duck/glTF-Embedded/Duck.gltf").unwrap();
    assert_eq!(glb.triangle_count(), 4212);
    assert_eq!(glb.positions.len(), 2399);
    assert_eq!(glb, emb, "the two copies of the Duck must give identical geometry");
    // The root node's scale 0.01 is applied (the raw positions span ~160 units).
    assert_bounds(&glb, [-0.69298, 0.09929, -0.61328], [0.9618, 1.6397, 0.53925], 1e-4);
}

#[test]
fn box_glb_and_gltf_with_external_bin_agree() {
    let glb = load("gltf/Box/glTF-Binary/Box.glb").unwrap();
    let sep = load("gltf/Box/glTF/Box.gltf").unwrap();
    assert_eq!(glb.triangle_count(), 12);
    assert_eq!(glb.positions.len(), 24);
    assert_eq!(glb, sep);
    assert_bounds(&glb, [-0.5; 3], [0.5; 3], 1e-6);
}

#[test]
fn box_gltf_without_its_bin_names_it() {
    let bytes = read(&data("gltf/Box/glTF/Box.gltf"));
    let e = load_mesh("models/Box.gltf", &bytes, &no_files).unwrap_err();
    assert_eq!(
        e,
        Error::MissingFile {
            file: "Box0.bin".into(),
            referrer: "models/Box.gltf".into()
        }
    );
    assert!(e.to_string().contains("Box0.bin"), "{e}");
}

#[test]
fn sparse_accessor_replaces_three_vertices() {
    let m = load("gltf/SimpleSparseAccessor/glTF-Embedded/SimpleSparseAccessor.gltf").unwrap();
    assert_eq!(m.positions.len(), 14);
    assert_eq!(m.triangle_count(), 12);
    for (i, p) in [(8, [1., 2., 0.]), (10, [3., 3., 0.]), (12, [5., 4., 0.])] {
        assert_eq!(m.positions[i], DVec3::from_array(p), "vertex {i}");
    }
    // The others keep the base 7×2 grid (vertex i at (i mod 7, i div 7, 0)).
    for (i, p) in [
        (7, [0., 1., 0.]),
        (9, [2., 1., 0.]),
        (11, [4., 1., 0.]),
        (13, [6., 1., 0.]),
    ] {
        assert_eq!(m.positions[i], DVec3::from_array(p), "vertex {i}");
    }
}

#[test]
fn engine_node_tree_is_flattened() {
    let m = load("gltf/2CylinderEngine/glTF-Binary/2CylinderEngine.glb").unwrap();
    assert_eq!(m.triangle_count(), 121496);
    assert_eq!(m.positions.len(), 84657);
    assert_bounds(&m, [-371.69, -180.97, -140.0], [371.69, 92.04, 128.0], 0.01);
}

#[test]
fn draco_is_rejected_by_name() {
    let e = load("gltf/2CylinderEngine/glTF-Draco-assimp/2CylinderEngine.gltf").unwrap_err();
    let msg = e.to_string();
    assert!(msg.contains("Draco-compressed meshes are not supported"), "{msg}");
    assert!(msg.contains("2CylinderEngine.gltf"), "{msg}");
}

#[test]
fn avocado_loads_without_its_textures() {
    let m = load("gltf/Avocado-kaolin/avocado.gltf").unwrap();
    assert_eq!(m.triangle_count(), 682);
    assert_eq!(m.positions.len(), 406);
    assert_bounds(&m, [-0.02128, -0.00005, -0.01381], [0.02128, 0.06285, 0.01381], 1e-5);
}

#[test]
fn truncated_glb_is_an_error() {
    let bytes = read(&data("gltf/Duck/glTF-Binary/Duck.glb"));
    for cut in [0, 3, 11, 12, 19, 20, 100, 1000, 4000, 50_000, 102_000, bytes.len() - 1] {
        let e = gltf::load("Duck.glb", &bytes[..cut], &no_files);
        match e {
            Err(Error::Mesh { file, problem }) => {
                assert_eq!(file, "Duck.glb");
                assert!(!problem.is_empty());
            }
            other => panic!("cut at {cut}: expected a mesh error, got {other:?}"),
        }
    }
    let e = gltf::load("Duck.glb", &bytes[..1000], &no_files)
        .unwrap_err()
        .to_string();
    assert!(e.contains("truncated"), "{e}");
}

/// A small deterministic generator (SplitMix64) for the mutation tests.
fn splitmix(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[test]
fn mutated_box_glb_never_panics() {
    let bytes = read(&data("gltf/Box/glTF-Binary/Box.glb"));
    let digits: Vec<usize> = (0..bytes.len()).filter(|&i| bytes[i].is_ascii_digit()).collect();
    let mut state = 42u64;
    let (mut ok, mut err) = (0, 0);
    for k in 0..3000 {
        let mut b = bytes.clone();
        let edits = 1 + splitmix(&mut state) % 3;
        for _ in 0..edits {
            let r = splitmix(&mut state);
            if k % 2 == 0 {
                // Any byte anywhere (headers, JSON, binary data) to any value.
                let i = (r % b.len() as u64) as usize;
                b[i] = (r >> 32) as u8;
            } else {
                // A digit of the JSON to another digit: still JSON, but counts,
                // offsets, lengths and indices go out of range.
                let i = digits[(r % digits.len() as u64) as usize];
                b[i] = b'0' + ((r >> 32) % 10) as u8;
            }
        }
        let result = std::panic::catch_unwind(|| gltf::load("Box.glb", &b, &no_files));
        match result {
            Ok(Ok(m)) => {
                assert!(m.validate("Box.glb").is_ok(), "mutation {k}: an Ok mesh must be valid");
                ok += 1
            }
            Ok(Err(_)) => err += 1,
            Err(_) => panic!("mutation {k} of Box.glb made the loader panic"),
        }
    }
    // Both outcomes occur, so the mutations reach past the first check.
    assert!(ok > 0 && err > 0, "ok {ok}, err {err}");
}

#[test]
fn nan_and_garbage_json_are_errors() {
    let text = String::from_utf8(read(&data("gltf/Box/glTF/Box.gltf"))).unwrap();
    let bin = read(&data("gltf/Box/glTF/Box0.bin"));
    let with_bin = move |uri: &str| (uri == "Box0.bin").then(|| bin.clone());
    assert!(gltf::load("Box.gltf", text.as_bytes(), &with_bin).is_ok());
    let nan = text.replacen("-1.0", "NaN", 1);
    assert_ne!(nan, text);
    let e = gltf::load("Box.gltf", nan.as_bytes(), &with_bin).unwrap_err();
    assert!(matches!(&e, Error::Mesh { file, .. } if file == "Box.gltf"), "{e}");
    let inf = text.replacen("-1.0", "1e999", 1);
    assert!(gltf::load("Box.gltf", inf.as_bytes(), &with_bin).is_err());
    for garbage in [
        "",
        "{",
        "[]",
        "{\"asset\": 3}",
        "not json at all",
        "{\"asset\":{\"version\":\"2.0\"}}",
    ] {
        let e = gltf::load("g.gltf", garbage.as_bytes(), &no_files).unwrap_err();
        assert!(e.to_string().starts_with("mesh 'g.gltf': "), "{garbage:?}: {e}");
    }
}

#[test]
fn obj_mesh_loads() {
    let m = load_at(crate::reference("pytorch3d-case1/mesh.obj"), "mesh.obj").unwrap();
    assert_eq!(m.positions.len(), 1026);
    assert_eq!(m.triangle_count(), 2048);
}
