#!/usr/bin/env bash
# Quick start, command 2 of 2: installs what is missing (tools/setup.sh), then runs the whole
# test suite on the local Vulkan device (lavapipe on a machine without a GPU) with the Khronos
# validation layer on. Extra arguments go to `cargo test`.
set -euo pipefail
cd "$(dirname "$0")/.."
source tools/env.sh
bash tools/setup.sh
echo "[test] cargo test (target folder: $CARGO_TARGET_DIR)"
cargo test --locked "$@"
