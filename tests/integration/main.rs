//! The fast tier of the native tests (`cargo test`): one binary, one module per area
//! (as tiny-skia does). The statistical and real-photograph checks are the second tier,
//! `tests/tier2` (`cargo test --test tier2`, run by `scripts/test.sh`).
#![cfg(not(target_arch = "wasm32"))]

mod ambiguity;
mod cli;
mod edge_raster;
mod estimator;
mod grasps;
mod hard_raster;
mod hostile;
mod importers;
mod limits;
mod mesh_loading;
mod metrics;
mod objective;
mod properties;
#[cfg(feature = "softras")]
mod soft_raster;

#[path = "../support/mod.rs"]
mod support;
pub use support::{data, fixture, reference, shared};
