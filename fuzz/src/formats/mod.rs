//! Valid-shaped inputs for every reader, written out as files, and the one way each is
//! fed to the library and its answer checked. Shared by the two tiers of issue item 1:
//! the fuzz targets (`fuzz/fuzz_targets/`, which fill these specs from `arbitrary`
//! structures) and the stable property tests (`tests/integration/properties.rs`, which
//! fill them from proptest strategies and include this file by `#[path]`).
//!
//! A spec is plain data (numbers may be anything, NaN included; indices and counts may
//! be out of range); the writers here serialise it by hand — a JSON number that is not
//! finite becomes a token no JSON parser takes (`NaN`, `1e999`), a PNG is written
//! chunk by chunk (stored deflate blocks), a glTF's accessors and views are laid out
//! from the spec's offsets and deltas — so that the file is the spec, mistakes
//! included. [`mutate`] then damages the bytes. The `drive_*` functions are the
//! entry points the CLI and the wasm binding use; on `Ok` the `check_*` functions
//! assert what every accepted input must give: finite numbers, indices in range,
//! rotations that are rotations. They panic otherwise: that is the failure.

#![allow(dead_code)]

mod bop;
mod camera;
mod checks;
mod fileset;
mod gltf;
mod json;
mod mesh;
mod mutate;
mod nerf;
mod ply;
mod png;
mod scene;

pub use bop::*;
pub use camera::*;
pub use checks::*;
pub use fileset::*;
pub use gltf::*;
pub use json::*;
pub use mesh::*;
pub use mutate::*;
pub use nerf::*;
pub use ply::*;
pub use png::*;
pub use scene::*;

use std::collections::BTreeMap;

/// Files by path (as the resolver is asked for them).
pub type Files = BTreeMap<String, Vec<u8>>;

/// With `LOCALISEBOT_FUZZ_DUMP=DIR` in the environment, the drivers write the files
/// they are about to read into `DIR` (to see what an input was: `examples/replay.rs`).
pub fn dump(name: &str, bytes: &[u8]) {
    static DIR: std::sync::OnceLock<Option<std::path::PathBuf>> = std::sync::OnceLock::new();
    if let Some(dir) = DIR.get_or_init(|| std::env::var_os("LOCALISEBOT_FUZZ_DUMP").map(Into::into)) {
        let safe: String = name
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || c == '.' || c == '_' || c == '-' {
                    c
                } else {
                    '+'
                }
            })
            .collect();
        let _ = std::fs::create_dir_all(dir);
        let _ = std::fs::write(dir.join(safe), bytes);
    }
}

fn dump_files(files: &Files) {
    for (k, v) in files {
        dump(k, v);
    }
}

/// A resolver over `files`.
pub fn resolver(files: &Files) -> impl Fn(&str) -> Option<Vec<u8>> + '_ {
    move |p: &str| files.get(p).cloned()
}
