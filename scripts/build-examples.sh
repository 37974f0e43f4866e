#!/usr/bin/env bash
# Builds the web page's examples into www/examples/ (ignored by git) with the command
# line (the release build; CLI_PROFILE=dev builds and uses the dev one instead), and
# www/examples/index.json listing them ({"examples": [{id, title, path}]}, path
# relative to index.json), which "Load example" offers:
#
#   toy   the project's procedural toy aeroplane (src/app/shapes.rs), 4 views: always;
#   duck  the Khronos Duck, read where it is in ../shared/data (the shared third-party
#         data beside the repository), 4 views: when ../shared is there;
#   lmo-duck  real photographs: three Linemod-Occluded views of the duck (Kinect,
#         640×480), imported with `import bop`, the other objects as ignore masks:
#         when ../shared/data/real/lmo is there.
#   lmo-duck-photos  the same photographs without masks: boxes (as a person drags
#         them) on two, the third's proposed by the geometry; the page segments them
#         (the segmenter: scripts/build-segmenter.sh). When ../shared/data/real/lmo is there.
#
# Adding an example is one `example ID "TITLE" COMMAND...` line below: COMMAND is run
# with `--out www/examples/ID` appended and must write ID/scene.json and the files it
# names (e.g. `$B import bop ...` for a real photograph).
#
#   scripts/build-examples.sh [OUT_DIR]      # default www/examples
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$HOME/.cargo/bin:$PATH"
OUT=${1:-www/examples}
SHARED=../shared/data
PROFILE=${CLI_PROFILE:-release}
# The dev build with the examples, as `cargo test` builds it: their dev-dependencies
# change a few crates' features, and alone the binary would be compiled again.
cargo build --locked --profile "$PROFILE" --bin localisebot $([ "$PROFILE" = dev ] && echo --examples)
B=${CARGO_TARGET_DIR:-target}/$([ "$PROFILE" = dev ] && echo debug || echo "$PROFILE")/localisebot
rm -rf "$OUT"
mkdir -p "$OUT"
ENTRIES=()

# example ID TITLE COMMAND...: runs COMMAND --out OUT/ID and lists the example.
example() {
  local id=$1 title=$2
  shift 2
  "$@" --out "$OUT/$id"
  [ -f "$OUT/$id/scene.json" ] || { echo "example '$id': $OUT/$id/scene.json was not written" >&2; exit 1; }
  ENTRIES+=("{\"id\": \"$id\", \"title\": \"$title\", \"path\": \"$id/scene.json\"}")
}

example toy "Toy aeroplane (procedural, 4 views)" \
  "$B" synth --shape toy --views 4 --seed 7 --images --grasps 6
if [ -f "$SHARED/gltf/Duck/glTF-Binary/Duck.glb" ]; then
  example duck "Duck (Khronos glTF sample, 4 views)" \
    "$B" synth --mesh "$SHARED/gltf/Duck/glTF-Binary/Duck.glb" --views 4 --seed 7 --images --grasps 6
else
  echo "note: $SHARED/gltf/Duck/glTF-Binary/Duck.glb not found (../shared must sit beside the" \
    "repository): the Duck example is left out" >&2
fi

if [ -f "$SHARED/real/lmo/test/000002/scene_gt.json" ]; then
  # Views 102, 362, 476: the duck at least 95 % visible, seen from directions 50°+ apart.
  example lmo-duck "Real photographs: Linemod-Occluded duck (3 views)" \
    "$B" import bop "$SHARED/real/lmo" --scene 2 --object 9 --images 102,362,476 --masks visib --ignore others
  example lmo-duck-photos "Real photographs without masks: the duck, boxes on 2 of 3 views" \
    "$B" import bop "$SHARED/real/lmo" --scene 2 --object 9 --images 102,362,476 --masks visib --boxes --boxes-in 2
else
  echo "note: $SHARED/real/lmo not found: the real-photograph example is left out" >&2
fi

{
  echo '{"examples": ['
  for i in "${!ENTRIES[@]}"; do
    sep=","; [ "$i" -eq $((${#ENTRIES[@]} - 1)) ] && sep=""
    echo "  ${ENTRIES[$i]}$sep"
  done
  echo ']}'
} > "$OUT/index.json"
echo "built ${#ENTRIES[@]} example(s) in $OUT: $(cd "$OUT" && ls -d -- */ | tr -d / | tr '\n' ' ')"
