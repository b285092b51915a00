#!/usr/bin/env bash
# Quick start, command 1 of 2: installs what is missing (tools/setup.sh), builds hybrid-rt (the
# dev profile, which Cargo.toml optimises) and renders the built-in default scene (the Cornell
# box) to out/default.png.
# Extra arguments go to `hybrid-rt render`, e.g. `tools/render-default.sh --size 1280x720`.
set -euo pipefail
cd "$(dirname "$0")/.."
source tools/env.sh
bash tools/setup.sh
# The default features: the shaders are the SPIR-V committed in shaders-spv/, so no shader
# compiler is built (tools/test.sh builds one).
echo "[render-default] building (the first build takes a few minutes)"
cargo build --locked
# The quick start owns out/default.png, so it replaces its own earlier result.
"$CARGO_TARGET_DIR/debug/hybrid-rt" render --size 640x640 --frames 8 --out out/default.png --force "$@"
echo "[render-default] image: $(pwd)/out/default.png"
