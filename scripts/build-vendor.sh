#!/usr/bin/env bash
# Copies the page's browser libraries from vendor/node_modules (vendor/package.json,
# exact versions, vendor/package-lock.json) into www/vendor/ (ignored by git), where
# www/index.html's import map finds them as ES modules — no bundler:
#
#   www/vendor/three/three.module.js, three.core.js   "three"
#   www/vendor/three/addons/controls/OrbitControls.js  "three/addons/controls/OrbitControls.js"
#   www/vendor/three/LICENSE
#
# Runs `npm ci --prefix vendor` first when vendor/node_modules lacks three (npm registry).
#
#   scripts/build-vendor.sh [OUT_DIR]      # default www/vendor
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-www/vendor}
SRC=vendor/node_modules/three
WANT=$(sed -n 's/.*"three": *"\([^"]*\)".*/\1/p' vendor/package.json | head -n1)
HAVE=$( [ -f "$SRC/package.json" ] && sed -n 's/^ *"version": *"\([^"]*\)".*/\1/p' "$SRC/package.json" | head -n1 || true)
if [ "$HAVE" != "$WANT" ]; then
  npm ci --prefix vendor --no-audit --no-fund --loglevel=error
fi
rm -rf "$OUT/three"
mkdir -p "$OUT/three/addons/controls"
cp "$SRC/build/three.module.js" "$OUT/three/"
# three ≥ 0.171 splits the module: three.module.js imports ./three.core.js.
[ -f "$SRC/build/three.core.js" ] && cp "$SRC/build/three.core.js" "$OUT/three/"
cp "$SRC/examples/jsm/controls/OrbitControls.js" "$OUT/three/addons/controls/"
cp "$SRC/LICENSE" "$OUT/three/LICENSE"
echo "copied three $WANT into $OUT/three"
