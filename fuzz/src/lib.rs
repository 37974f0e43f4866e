//! Fuzzing of LocaliseBot-rs's readers (issue item 1): structure-aware inputs for
//! every reader, serialised to the format and damaged, fed to the entry points the
//! CLI and the wasm binding use. See README.md.
//!
//! - [`formats`]: the specs and their writers, the drivers and the checks (shared
//!   with the stable property tests, `tests/integration/properties.rs`);
//! - [`arb`]: the `arbitrary` structures the targets decode;
//! - [`targets`]: the targets' bodies.

pub mod arb;
pub mod formats;
pub mod targets;

/// The JPEG writers of the main crate's tests (`tests/support/jpeg.rs`), for the seeds.
#[path = "../../tests/support/jpeg.rs"]
mod jpeg_support;
