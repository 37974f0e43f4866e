//! `localisebot info MESH`: counts and bounds of a mesh after node transforms.

use super::files::{load_mesh, to_json, CliResult};
use std::path::Path;

/// Prints `{"vertices", "triangles", "bounds": {"min", "max"}}`.
pub fn run(path: &Path) -> CliResult {
    let mesh = load_mesh(path)?;
    let b = mesh
        .bounds()
        .ok_or_else(|| format!("{}: mesh has no vertices", path.display()))?;
    let out = serde_json::json!({
        "vertices": mesh.positions.len(),
        "triangles": mesh.triangles.len(),
        "bounds": { "min": b.min.to_array(), "max": b.max.to_array() },
        "diameter": mesh.diameter(),
    });
    println!("{}", to_json(&out));
    Ok(())
}
