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
echo "== wasm tests in headless Chromium and in Node"
if command -v wasm-pack >/dev/null; then
  # wasm-pack uses the wasm-bindgen-test-runner on PATH when its version matches Cargo.lock.
  wasm-pack test --headless --chrome --chromedriver "$(command -v chromedriver)" -- --locked --test wasm
  wasm-pack test --node -- --locked --test wasm_node
else
  echo "(wasm-pack not installed: running wasm-bindgen-test-runner directly)"
  CARGO_TARGET_WASM32_UNKNOWN_UNKNOWN_RUNNER=wasm-bindgen-test-runner \
    cargo test --locked --target wasm32-unknown-unknown --test wasm --test wasm_node
fi
echo "== the web page, end to end (Playwright + Chromium)"
bash scripts/build-wasm.sh
node tests/e2e/page.test.mjs
echo "== the npm package (pkg-config/): build, npm pack, load in Node"
bash pkg-config/build.sh
node pkg-config/smoke.mjs
