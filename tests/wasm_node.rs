//! The WebAssembly suite in Node (`tests/wasm_common`): run with `wasm-pack test --node`,
//! or `cargo test --target wasm32-unknown-unknown --test wasm_node` with
//! `CARGO_TARGET_WASM32_UNKNOWN_UNKNOWN_RUNNER=wasm-bindgen-test-runner`.
#![cfg(target_arch = "wasm32")]

mod wasm_common;
