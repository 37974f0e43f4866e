//! The second tier of the native tests: statistical checks over many fitted scenes and
//! the fits of real photographs (`../shared/data/real/lmo`). Minutes, not seconds, so
//! not in `cargo test`: `cargo test --test tier2` (`scripts/test.sh` runs it).
#![cfg(not(target_arch = "wasm32"))]

mod ambiguity;
mod cameras;
mod jpeg;
mod occlusion;
mod photos;
mod real;
mod segmenter;
mod uncertainty;

#[path = "../support/mod.rs"]
mod support;
pub use support::{coverage, data, fixture, reference, shared};
