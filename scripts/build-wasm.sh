#!/usr/bin/env bash
# Builds the WebAssembly package the web page loads: the library for
# wasm32-unknown-unknown (release), then wasm-bindgen's ES-module glue and
# TypeScript declarations into www/pkg/ (ignored by git), then optimises the wasm with
# wasm-opt -O3 (binaryen 132 from npm, installed in tools/node_modules by
# scripts/setup.sh; `npm ci --prefix tools`). Prints the wasm's size, raw and gzipped,
# before and after wasm-opt. WASM_OPT_SKIP=1 leaves the wasm as wasm-bindgen wrote it.
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
WASM_OPT_BIN=tools/node_modules/.bin/wasm-opt
if [ "${WASM_OPT_SKIP:-}" != 1 ] && ! "$WASM_OPT_BIN" --version 2>/dev/null | grep -q 'version 132'; then
  echo "wasm-opt (binaryen 132, tools/package.json) is needed: run scripts/setup.sh" \
    "(or: npm ci --prefix tools)" >&2
  exit 1
fi
# Without the cargo feature `softras` (the reference renderer stays native).
cargo build --locked --release --lib --no-default-features --target wasm32-unknown-unknown
rm -rf "$OUT"
wasm-bindgen --target web --out-dir "$OUT" "${CARGO_TARGET_DIR:-target}/wasm32-unknown-unknown/release/localisebot.wasm"
WASM="$OUT/localisebot_bg.wasm"
sizes() { echo "$(wc -c < "$1") bytes, $(gzip -9 < "$1" | wc -c) gzipped (gzip -9)"; }
echo "wasm-bindgen: $WASM $(sizes "$WASM")"
if [ "${WASM_OPT_SKIP:-}" = 1 ]; then
  echo "WASM_OPT_SKIP=1: wasm-opt not run"
  exit 0
fi
# The features rustc's wasm32-unknown-unknown target emits (its target_features
# section: bulk-memory, multivalue, mutable-globals, nontrapping-fptoint,
# reference-types, sign-ext, and simd128 from .cargo/config.toml), enabled explicitly
# over the MVP so that wasm-opt refuses anything else. -O3 rather than -Oz: -Oz saves
# another 4 % raw but only 0.2 % gzipped; the fit times of the unoptimised, -O3 and -Oz
# builds were within this VM's noise (docs/benchmark-history.md, "Browser"). wasm-opt drops the name
# section (function names, 189 KB) unless given -g.
FEATURES=(--mvp-features --enable-bulk-memory --enable-bulk-memory-opt --enable-call-indirect-overlong
  --enable-multivalue --enable-mutable-globals --enable-nontrapping-float-to-int --enable-reference-types
  --enable-sign-ext --enable-simd)
"$WASM_OPT_BIN" "${FEATURES[@]}" -O3 "$WASM" -o "$WASM.opt"
mv "$WASM.opt" "$WASM"
echo "wasm-opt -O3:  $WASM $(sizes "$WASM")"
echo "built $OUT"
