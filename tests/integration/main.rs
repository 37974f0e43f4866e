//! Native integration tests: one binary, one module per area (as tiny-skia does).
#![cfg(not(target_arch = "wasm32"))]

mod cli;
mod edge_raster;
mod estimator;
mod grasps;
mod hard_raster;
mod importers;
mod mesh_loading;
mod metrics;
mod soft_raster;

/// Path to a file under `../shared` (the shared third-party data beside the repo).
pub fn shared(rel: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("shared")
        .join(rel)
}

/// Path to a file under `tests/fixtures`.
pub fn fixture(rel: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests")
        .join("fixtures")
        .join(rel)
}
