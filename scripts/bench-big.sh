#!/usr/bin/env bash
# Big but legitimate input: a 1,000,000-triangle mesh (examples/big_scene.rs) seen by
# eight 4032×3024 views with masks and shaded images (`localisebot synth`), written to
# target/big-scene (ignored by git); then the command line fits it under
# `/usr/bin/time -v` (wall time, peak RSS) and prints the result's verdict and ADD
# against the scene's ground truth; then the page fits it (tests/e2e/big.test.mjs: the
# tab's memory, sampled every second). Figures in BENCHMARKS.md ("Big input").
#
#   bash scripts/bench-big.sh            # BIG_KEEP=1 reuses an existing target/big-scene
#                                        # LOCALISEBOT=PATH uses that binary instead of building
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$HOME/.cargo/bin:$PATH"
T=${CARGO_TARGET_DIR:-target}
SCENE=target/big-scene
OUT=target/big-scene-cli
if [ -z "${LOCALISEBOT:-}" ]; then
  cargo build --locked --release --bin localisebot --example big_scene
  B=$T/release/localisebot
else
  cargo build --locked --release --example big_scene
  B=$LOCALISEBOT
fi
mkdir -p "$OUT"
if [ "${BIG_KEEP:-}" != 1 ] || [ ! -f "$SCENE/scene.json" ]; then
  rm -rf "$SCENE"
  "$T/release/examples/big_scene" "$OUT/mesh"
  /usr/bin/time -f '%e s wall, %M KB peak RSS' -o "$OUT/synth.time" \
    "$B" synth --mesh "$OUT/mesh/big.glb" --views 8 --width 4032 --height 3024 --seed 1 --images --out "$SCENE"
  echo "synth: $(cat "$OUT/synth.time")"
fi
echo "scene: $(du -sh "$SCENE" | cut -f1) in $SCENE; mesh: $("$B" info "$SCENE/big.glb" | jq -c '{vertices, triangles, diameter}')"

/usr/bin/time -v -o "$OUT/fit.time" "$B" fit "$SCENE/scene.json" --out "$OUT/result.json"
wall=$(sed -n 's/.*Elapsed (wall clock) time (h:mm:ss or m:ss): //p' "$OUT/fit.time")
rss=$(sed -n 's/.*Maximum resident set size (kbytes): //p' "$OUT/fit.time")
echo "CLI fit: wall $wall, peak RSS $((rss / 1024)) MB ($rss KB)"
jq -r '"CLI result: verdict \(.verdict) \(.verdict_reasons), termination \(.termination), \(.iterations) iterations, "
  + "\(.seconds * 10 | round / 10) s; mean IoU \(.mean_iou * 10000 | round / 10000); ADD \(.errors.add_rel * 100000 | round / 1000) % of the diameter "
  + "(\(.errors.add * 1e6 | round / 1000) mm), rotation \(.errors.rotation_deg * 1000 | round / 1000) deg, scale \(.errors.scale * 10000 | round / 100) %"' \
  "$OUT/result.json"

node tests/e2e/big.test.mjs
