//! Real glTF files parsed in WebAssembly (Node): the Khronos Duck (`.glb` and the
//! embedded `.gltf`) and Box (`.glb` and `.gltf` + `.bin`) of the shared third-party
//! data. A wasm test cannot read files, so they are compiled in with `include_bytes!`
//! from where they are, `../shared/data/gltf` beside the repository (never copied
//! into it): without that folder this suite does not build, and the compiler names the
//! missing file. Run with `wasm-pack test --node -- --test wasm_shared`.
#![cfg(target_arch = "wasm32")]

use localisebot::io::{load_mesh, no_files};
use localisebot::wasm::{check_mesh, FileSet};
use localisebot::Mesh;
use wasm_bindgen_test::wasm_bindgen_test;

const DUCK_GLB: &[u8] = include_bytes!("../../shared/data/gltf/Duck/glTF-Binary/Duck.glb");
const DUCK_GLTF: &[u8] = include_bytes!("../../shared/data/gltf/Duck/glTF-Embedded/Duck.gltf");
const BOX_GLB: &[u8] = include_bytes!("../../shared/data/gltf/Box/glTF-Binary/Box.glb");
const BOX_GLTF: &[u8] = include_bytes!("../../shared/data/gltf/Box/glTF/Box.gltf");
const BOX_BIN: &[u8] = include_bytes!("../../shared/data/gltf/Box/glTF/Box0.bin");

fn same_mesh(a: &Mesh, b: &Mesh, tol: f64) {
    assert!(a.triangles == b.triangles, "the same triangles");
    assert_eq!(a.positions.len(), b.positions.len());
    for (p, q) in a.positions.iter().zip(&b.positions) {
        assert!((*p - *q).abs().max_element() <= tol, "{p} vs {q}");
    }
}

#[wasm_bindgen_test]
fn khronos_meshes_load_alike_from_glb_gltf_and_buffers() {
    let glb = load_mesh("Duck.glb", DUCK_GLB, &no_files).unwrap();
    let gltf = load_mesh("Duck.gltf", DUCK_GLTF, &no_files).unwrap();
    assert_eq!(glb.triangles.len(), 4212);
    same_mesh(&glb, &gltf, 1e-6);
    // The root node's scale 0.01 is applied (SOURCES.md: world AABB max y 1.6397).
    let b = glb.bounds().unwrap();
    assert!((b.max.y - 1.6397).abs() < 1e-3, "{}", b.max);

    let box_glb = load_mesh("Box.glb", BOX_GLB, &no_files).unwrap();
    let bin = |uri: &str| (uri == "Box0.bin").then(|| BOX_BIN.to_vec());
    let box_gltf = load_mesh("Box.gltf", BOX_GLTF, &bin).unwrap();
    assert_eq!(box_gltf.triangles.len(), 12);
    same_mesh(&box_glb, &box_gltf, 1e-12);
    // Through the binding: the .bin found by name in a FileSet.
    let mut extra = FileSet::new();
    extra.add_bytes("Box0.bin", BOX_BIN.to_vec());
    assert_eq!(check_mesh("models/Box.gltf", BOX_GLTF, &extra).unwrap(), 12);
}
