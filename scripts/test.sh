#!/usr/bin/env bash
# The whole test suite: formatting, clippy, native tests (the fast tier, then the
# second: statistical and real-photograph checks), the wasm32 build, the wasm
# tests in headless Chromium and Node, the web page end to end (after building the
# wasm package and the page's examples), the npm package.
#
# Every step runs even when an earlier one failed, and the failures are listed at the
# end (exit status 1). Tests that read the shared third-party data (`../shared`,
# beside the repository) fail, with a message naming the folder, when it is missing;
# nothing is skipped.
set -uo pipefail
cd "$(dirname "$0")/.."
export PATH="$HOME/.cargo/bin:$PATH"

SHARED_NOTE=""
if [ ! -d ../shared/data ]; then
  SHARED_NOTE="../shared (the shared third-party data: data/, reference/) is not beside the repository at $(cd .. && pwd)/shared: the tests that read it fail."
  echo "warning: $SHARED_NOTE" >&2
fi

FAILED=()
TIMES=() # each step's wall time, listed at the end: what to move to a later tier when the run grows
LOGS=target/test-logs # each step's output, kept so that a failure's cause is repeated at the end
rm -rf "$LOGS" && mkdir -p "$LOGS"
STEP_N=0
step() { # step NAME COMMAND...
  local name=$1
  shift
  STEP_N=$((STEP_N + 1))
  local log
  log=$(printf '%s/%02d.log' "$LOGS" "$STEP_N")
  echo "== $name"
  local t0=$SECONDS
  if ! "$@" 2>&1 | tee "$log"; then
    FAILED+=("$name")
    echo "!! FAILED: $name" >&2
    echo "$name" >"$log.failed"
  fi
  TIMES+=("$(printf '%5d s  %s' $((SECONDS - t0)) "$name")")
}

# wasm-bindgen-test-runner gives the browser's whole run 20 s and chromedriver 5 s to
# start by default; a fresh, busy machine can take longer (a CI run failed so, once).
# A hang still ends, after these.
export WASM_BINDGEN_TEST_TIMEOUT=${WASM_BINDGEN_TEST_TIMEOUT:-300}
export WASM_BINDGEN_TEST_DRIVER_TIMEOUT=${WASM_BINDGEN_TEST_DRIVER_TIMEOUT:-60}

wasm_tests() { # wasm_tests (browser|node) TEST_TARGET... — built as the shipped wasm is (no `softras`)
  local where=$1
  shift
  local tests=()
  for t in "$@"; do tests+=(--test "$t"); done
  if command -v wasm-pack >/dev/null; then
    # wasm-pack uses the wasm-bindgen-test-runner on PATH when its version matches Cargo.lock.
    if [ "$where" = browser ]; then
      wasm-pack test --headless --chrome --chromedriver "$(command -v chromedriver)" -- --locked --no-default-features "${tests[@]}"
    else
      wasm-pack test --node -- --locked --no-default-features "${tests[@]}"
    fi
  else
    echo "(wasm-pack not installed: running wasm-bindgen-test-runner directly)"
    CARGO_TARGET_WASM32_UNKNOWN_UNKNOWN_RUNNER=wasm-bindgen-test-runner \
      cargo test --locked --no-default-features --target wasm32-unknown-unknown "${tests[@]}"
  fi
}

# The command line and the examples the later steps run are the dev build the native
# tests made (the dev profile is optimised, opt-level 2, and fits as fast as release):
# building the release profile as well would compile every dependency (tract, the
# segmenter's engine, among them) a second time, ten minutes on two cores.
export CLI_PROFILE=dev
# A clean run builds once: incremental compilation's caches would only cost disk.
export CARGO_INCREMENTAL=${CARGO_INCREMENTAL:-0}

# The disk the build writes to, before and after: a machine that runs out fails every
# later step with "No space left on device" (a CI run did, once).
disk() { df -h --output=avail,size,target . 2>/dev/null | tail -n 1; }
echo "disk free at the start: $(disk)"

step "cargo fmt --check" cargo fmt --all -- --check
step "cargo clippy" cargo clippy --workspace --all-targets --locked -- -D warnings
step "cargo doc (the crate's manual: no broken links, every public item documented)" \
  env RUSTDOCFLAGS="-D warnings" cargo doc --locked --no-deps
step "cargo clippy (the second tier of tests)" cargo clippy --test tier2 --locked -- -D warnings
step "native tests (fast tier: cargo test)" cargo test --workspace --locked --no-fail-fast
step "native tests, second tier (statistical checks, real photographs)" cargo test --locked --no-fail-fast --test tier2
step "wasm32 build of the library" cargo build --locked --lib --release --no-default-features --target wasm32-unknown-unknown
step "wasm tests in headless Chromium" wasm_tests browser wasm
step "wasm tests in Node" wasm_tests node wasm_node
# Real glTF files of ../shared compiled in with include_bytes!: without ../shared this
# suite does not build, and the compiler names the missing file.
step "wasm tests in Node on the shared glTF files" wasm_tests node wasm_shared
step "the wasm package (www/pkg)" bash scripts/build-wasm.sh
step "the page's examples (www/examples)" bash scripts/build-examples.sh
step "the page's browser libraries (www/vendor: three.js)" bash scripts/build-vendor.sh
step "the segmenter's wasm module and weights for the page (www/pkg-segment, www/models)" bash scripts/build-segmenter.sh
step "the examples a user learns from (examples/: a scene built in code, a scene file fitted)" \
  bash -c 'cargo run --locked --profile "$CLI_PROFILE" --example build_scene && for s in www/examples/*/scene.json; do cargo run --locked --profile "$CLI_PROFILE" --example fit_scene -- "$s" || exit 1; done'
step "the web page, end to end (Playwright + Chromium)" node tests/e2e/page.test.mjs
step "the page's 3D view, end to end (Playwright + Chromium, WebGL on SwiftShader)" node tests/e2e/view3d.test.mjs
step "the page from photographs and boxes, end to end (Playwright + Chromium: segmenter in Workers)" node tests/e2e/photos.test.mjs
step "the page under abuse, end to end (Playwright + Chromium: loads racing, clicks mid-step, Workers ended)" node tests/e2e/abuse.test.mjs
step "big input: eight 12-MP views and a 1-M-triangle mesh, fitted by the command line and in the page within its memory budget" \
  bash scripts/bench-big.sh
step "the npm package (pkg-config/): build, npm pack, load in Node" \
  bash -c 'bash pkg-config/build.sh && node pkg-config/smoke.mjs'

echo
echo "disk free at the end: $(disk) (the build: $(du -sh target 2>/dev/null | cut -f1))"
echo "each step's wall time (the whole run: $SECONDS s):"
printf '  %s\n' "${TIMES[@]}"
if [ ${#FAILED[@]} -eq 0 ]; then
  echo "all steps passed"
  exit 0
fi
for f in "$LOGS"/*.failed; do # the end of each failed step's output, where its cause is
  echo "-- the last 40 lines of: $(cat "$f")" >&2
  tail -n 40 "${f%.failed}" >&2
done
echo "FAILED steps (${#FAILED[@]}):" >&2
printf '  - %s\n' "${FAILED[@]}" >&2
[ -n "$SHARED_NOTE" ] && echo "note: $SHARED_NOTE" >&2
exit 1
