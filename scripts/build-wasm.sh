#!/usr/bin/env bash
# Builds the WebAssembly package the web page loads: the library for
# wasm32-unknown-unknown (release), then wasm-bindgen's ES-module glue and
# TypeScript declarations into www/pkg/ (ignored by git).
#
#   scripts/build-wasm.sh [OUT_DIR]      # default www/pkg
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$HOME/.cargo/bin:$PATH"
OUT=${1:-www/pkg}
WB=$(grep -A1 '^name = "wasm-bindgen"$' Cargo.lock | sed -n 's/^version = "\(.*\)"/\1/p' | head -n1)
if ! wasm-bindgen --version 2>/dev/null | grep -qx "wasm-bindgen ${WB:-0.2.130}"; then
  echo "wasm-bindgen CLI ${WB:-0.2.130} is needed (Cargo.lock pins it): run scripts/setup.sh" >&2
  exit 1
fi
cargo build --locked --release --lib --target wasm32-unknown-unknown
rm -rf "$OUT"
wasm-bindgen --target web --out-dir "$OUT" "${CARGO_TARGET_DIR:-target}/wasm32-unknown-unknown/release/localisebot.wasm"
echo "built $OUT ($(du -k "$OUT/localisebot_bg.wasm" | cut -f1) KiB of wasm)"
