#!/usr/bin/env bash
# Builds the npm package `localisebot` from the wasm build: wasm-bindgen's ES module
# (--target web: browsers without a bundler, and Node via initSync), its TypeScript
# declarations, pkg-config/package.json (version taken from Cargo.toml) and
# pkg-config/README.md; then `npm pack` it.
#
#   pkg-config/build.sh [OUT_DIR]    # default target/npm; the package is OUT_DIR/localisebot,
#                                    # the tarball OUT_DIR/localisebot-VERSION.tgz
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-target/npm}
PKG="$OUT/localisebot"
bash scripts/build-wasm.sh "$PKG"
VERSION=$(sed -n 's/^version = "\(.*\)"/\1/p' Cargo.toml | head -n1)
node -e '
  const fs = require("fs");
  const [src, dst, version] = process.argv.slice(1);
  const pkg = JSON.parse(fs.readFileSync(src, "utf8"));
  pkg.version = version;
  for (const f of pkg.files) if (!fs.existsSync(`${require("path").dirname(dst)}/${f}`) && f !== "README.md")
    throw new Error(`package file ${f} was not built`);
  fs.writeFileSync(dst, JSON.stringify(pkg, null, 2) + "\n");
' pkg-config/package.json "$PKG/package.json" "$VERSION"
cp pkg-config/README.md "$PKG/README.md"
(cd "$OUT" && npm pack ./localisebot --pack-destination . --loglevel=warn)
echo "packed $OUT/localisebot-$VERSION.tgz"
