#!/usr/bin/env bash
# Big but legitimate input: a 1,000,000-triangle mesh (examples/big_scene.rs) seen by
# eight 4032×3024 views with masks and shaded images (`localisebot synth`), written to
# target/big-scene (ignored by git); then the command line fits it under
# `/usr/bin/time -v` (wall time, peak RSS) and prints the result's verdict and ADD
# against the scene's ground truth (failing when the verdict is failed, a number is not
# finite or ADD is 1 % of the diameter or more); then the page fits it
# (tests/e2e/big.test.mjs: the tab's memory, sampled every second, within its budget).
# scripts/test.sh runs this; figures in BENCHMARKS.md ("Big input").
#
#   bash scripts/bench-big.sh            # BIG_KEEP=1 reuses an existing target/big-scene
#                                        # LOCALISEBOT=PATH uses that binary instead of building
#                                        # CLI_PROFILE=dev builds the dev profile, not release
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$HOME/.cargo/bin:$PATH"
T=${CARGO_TARGET_DIR:-target}
PROFILE=${CLI_PROFILE:-release} # CLI_PROFILE=dev: the dev build (as scripts/test.sh has it)
D=$T/$([ "$PROFILE" = dev ] && echo debug || echo "$PROFILE")
SCENE=target/big-scene
OUT=target/big-scene-cli
if [ -z "${LOCALISEBOT:-}" ]; then
  cargo build --locked --profile "$PROFILE" --bin localisebot --example big_scene
  B=$D/localisebot
else
  cargo build --locked --profile "$PROFILE" --example big_scene
  B=$LOCALISEBOT
fi
mkdir -p "$OUT"
if [ "${BIG_KEEP:-}" != 1 ] || [ ! -f "$SCENE/scene.json" ]; then
  rm -rf "$SCENE"
  "$D/examples/big_scene" "$OUT/mesh"
  /usr/bin/time -f '%e s wall, %M KB peak RSS' -o "$OUT/synth.time" \
    "$B" synth --mesh "$OUT/mesh/big.glb" --views 8 --width 4032 --height 3024 --seed 1 --images --out "$SCENE"
  echo "synth: $(cat "$OUT/synth.time")"
fi
echo "scene: $(du -sh "$SCENE" | cut -f1) in $SCENE, mesh $(du -h "$SCENE/big.glb" | cut -f1)"

/usr/bin/time -v -o "$OUT/fit.time" "$B" fit "$SCENE/scene.json" --out "$OUT/result.json"
wall=$(sed -n 's/.*Elapsed (wall clock) time (h:mm:ss or m:ss): //p' "$OUT/fit.time")
rss=$(sed -n 's/.*Maximum resident set size (kbytes): //p' "$OUT/fit.time")
echo "CLI fit: wall $wall, peak RSS $((rss / 1024)) MB ($rss KB)"
node -e '
const r = JSON.parse(require("fs").readFileSync(process.argv[1], "utf8")), e = r.errors;
console.log(`CLI result: verdict ${r.verdict}${r.verdict_reasons.length ? ` (${r.verdict_reasons.join("; ")})` : ""}, ` +
  `termination ${r.termination}, ${r.iterations} iterations, ${r.seconds.toFixed(1)} s; mean IoU ${r.mean_iou.toFixed(4)}; ` +
  `ADD ${(e.add_rel * 100).toFixed(3)} % of the diameter (${(e.add * 1000).toFixed(3)} mm), ` +
  `rotation ${e.rotation_deg.toFixed(3)} deg, scale ${(e.scale * 100).toFixed(2)} %`);
const numbers = [...r.pose.translation, ...r.pose.scale, ...r.pose.quaternion, e.add_rel, r.mean_iou];
if (r.verdict === "failed" || !numbers.every(Number.isFinite) || !(e.add_rel < 0.01)) {
  console.error("the command line did not localise the big scene (verdict failed, a number not finite, or ADD >= 1 % d)");
  process.exit(1);
}' "$OUT/result.json"

node tests/e2e/big.test.mjs
