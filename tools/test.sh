#!/usr/bin/env bash
# Quick start, command 2 of 2: installs what is missing (tools/setup.sh), then runs the whole
# test suite on the local Vulkan device (lavapipe on a machine without a GPU) with the Khronos
# validation layer on, and checks that Cargo.toml's rust-version is the real minimum
# (tools/check-msrv.sh, over every feature). Extra arguments go to `cargo test`.
#
# The tests build with the `shader-compiler` feature (libshaderc from source: ~20 minutes on 2
# cores the first time): they compile shaders-glsl/ at run time (hot reload, `--shader-dir`) and
# check that shaders-spv/, the SPIR-V a default build embeds, is exactly what it compiles to.
#
# Every test binary runs even when one fails (--no-fail-fast); the end of the output lists each
# failing binary with its failing tests, and the last line totals all of them in the form of
# cargo's own `test result:` lines. The exit status is non-zero when anything failed. A binary
# that died by a signal before reporting (a crash, not a failed test) is run once more, and
# counts as passed only if that run passes; the last line then names it (tools/test_summary.py
# says why).
set -euo pipefail
cd "$(dirname "$0")/.."
source tools/env.sh
bash tools/setup.sh
python3 tools/test_summary.py --self-test

log=$(mktemp /tmp/hybrid-rt-test.XXXXXX.log)
echo "[test] cargo test --features shader-compiler --no-fail-fast (target folder: $CARGO_TARGET_DIR; log: $log)"
set +e
cargo test --locked --features shader-compiler --no-fail-fast "$@" 2>&1 | tee "$log"
cargo_status=${PIPESTATUS[0]}
reruns=()
for name in $(python3 tools/test_summary.py "$log" --crashed); do
    rerun_log=$(mktemp "/tmp/hybrid-rt-test-$name.XXXXXX.log")
    echo "[test] tests/$name.rs died by a signal: running it once more (log: $rerun_log)"
    cargo test --locked --features shader-compiler --test "$name" "$@" 2>&1 | tee "$rerun_log"
    reruns+=(--rerun "$rerun_log")
done
echo "[test] tools/check-msrv.sh"
bash tools/check-msrv.sh
msrv_status=$?
set -e

checks=()
if [ "$msrv_status" -eq 0 ]; then checks+=(--passed "msrv check"); else checks+=(--failed "msrv check (tools/check-msrv.sh)"); fi
echo "[test] summary"
exec python3 tools/test_summary.py "$log" --cargo-status "$cargo_status" "${checks[@]}" "${reruns[@]}"
