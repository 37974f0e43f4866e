//! Prints (does not assert) a mesh's levels of detail (`raster::lod`): triangles,
//! vertices and error of each level, the time to build them, and which level the
//! bench's 4 views at 128² choose at σ = 1 px².
//!
//! `cargo run --release --example lod_levels [mesh.glb …]` (default: the shared Duck
//! and 2CylinderEngine).

use localisebot::app::synth::{synthesize, SynthSettings};
use localisebot::raster::edge::EdgeTopology;
use localisebot::raster::lod::{DetailLevels, DEFAULT_DETAIL_PX};
use std::time::Instant;

fn main() {
    let mut paths: Vec<String> = std::env::args().skip(1).collect();
    if paths.is_empty() {
        let d = concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/data/gltf");
        paths = vec![
            format!("{d}/Duck/glTF-Binary/Duck.glb"),
            format!("{d}/2CylinderEngine/glTF-Binary/2CylinderEngine.glb"),
        ];
    }
    for path in &paths {
        let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{path}: {e}"));
        let mesh = localisebot::io::load_mesh(path, &bytes, &|_| None).unwrap_or_else(|e| panic!("{e}"));
        let t = Instant::now();
        let d = DetailLevels::build(&mesh, &EdgeTopology::from_mesh(&mesh), DEFAULT_DETAIL_PX);
        println!(
            "{path}: {} triangles, {} vertices, diameter {:.4}; welded in {:.0} ms",
            mesh.triangles.len(),
            mesh.positions.len(),
            mesh.diameter(),
            t.elapsed().as_secs_f64() * 1e3
        );
        for k in 0..d.len() {
            let t = Instant::now();
            let level = d.level(k);
            let ms = t.elapsed().as_secs_f64() * 1e3;
            match level {
                Some(l) => println!(
                    "  level {k:2} (bound diameter/{:4.0}): {:7} triangles {:7} vertices, error {:.3e}, built in {ms:.0} ms",
                    mesh.diameter() / d.bound(k),
                    l.mesh.triangles.len(),
                    l.mesh.positions.len(),
                    l.error
                ),
                None => println!("  level {k:2}: saves too little, built in {ms:.0} ms"),
            }
        }
        let settings = SynthSettings {
            views: 4,
            width: 128,
            height: 128,
            seed: 11,
            ..Default::default()
        };
        let s = synthesize(&mesh, &settings, None).unwrap_or_else(|e| panic!("{e}"));
        for (v, cam) in s.cameras.iter().enumerate() {
            let chosen = d.choose(&s.pose, cam, 1.0);
            println!(
                "  bench view {v} (128², σ = 1): {}",
                chosen.map_or("the mesh itself".to_string(), |l| format!(
                    "{} triangles",
                    l.mesh.triangles.len()
                ))
            );
        }
    }
}
