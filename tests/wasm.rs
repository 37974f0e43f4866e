//! The WebAssembly suite in headless Chromium (`tests/wasm_common`): run with
//! `wasm-pack test --headless --chrome`, or `cargo test --target wasm32-unknown-unknown
//! --test wasm` with `CARGO_TARGET_WASM32_UNKNOWN_UNKNOWN_RUNNER=wasm-bindgen-test-runner`.
#![cfg(target_arch = "wasm32")]

wasm_bindgen_test::wasm_bindgen_test_configure!(run_in_browser);

mod wasm_common;
