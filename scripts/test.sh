#!/usr/bin/env bash
# The whole test suite: formatting, clippy, native tests, the wasm32 build.
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$HOME/.cargo/bin:$PATH"

echo "== cargo fmt --check"
cargo fmt --all -- --check
echo "== cargo clippy"
cargo clippy --all-targets --locked -- -D warnings
echo "== native tests"
cargo test --locked
echo "== wasm32 build of the library"
cargo build --locked --lib --release --target wasm32-unknown-unknown
