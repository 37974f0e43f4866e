#!/usr/bin/env bash
# The README's first command: builds the wasm package into www/pkg/ and serves www/
# on http://127.0.0.1:8080/ (the example is one click away: "Load example").
# Ctrl-C stops the server.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build-wasm.sh
echo "open http://127.0.0.1:8080/ and click 'Load example' (Ctrl-C stops the server)"
exec node scripts/serve.mjs --root www --host 127.0.0.1 --port "${PORT:-8080}"
