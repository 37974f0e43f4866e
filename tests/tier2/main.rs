//! The second tier of the native tests: statistical checks over many fitted scenes and
//! the fits of real photographs (`../shared/data/real/lmo`). Minutes, not seconds, so
//! not in `cargo test`: `cargo test --test tier2` (`scripts/test.sh` runs it).
#![cfg(not(target_arch = "wasm32"))]

mod ambiguity;
mod annotation;
mod boxes;
mod cameras;
mod jpeg;
mod occlusion;
mod outlines;
mod photos;
mod real;
mod segmenter;
mod uncertainty;

#[path = "../support/mod.rs"]
mod support;
pub use support::{coverage, data, fixture, reference, shared};

/// Runs the release command line built with these tests, asserting that it succeeds
/// (its error output in the message otherwise); returns what it wrote to stderr.
pub fn localisebot(args: &[&str]) -> String {
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_localisebot"))
        .args(args)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(o.status.success(), "{args:?}: {err}");
    err
}

/// `localisebot import bop` of the LM-O scene 2's `object` in `images` ("A,B,C") with
/// boxes made from its visible masks instead of masks (the photograph path), into `out`.
pub fn import_lmo_boxes(object: u32, images: &str, out: &std::path::Path) {
    localisebot(&[
        "import",
        "bop",
        data("real/lmo").to_str().unwrap(),
        "--scene",
        "2",
        "--object",
        &object.to_string(),
        "--images",
        images,
        "--masks",
        "visib",
        "--boxes",
        "--out",
        out.to_str().unwrap(),
    ]);
}
