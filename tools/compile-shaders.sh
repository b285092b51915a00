#!/usr/bin/env bash
# Recompiles shaders-glsl/ into shaders-spv/ (the SPIR-V a default build embeds) and rewrites
# shaders-spv/manifest.txt. Run it after editing, adding or removing any GLSL file, then commit
# shaders-spv/ with the GLSL: a default build fails, naming the files, while they disagree.
#
# It builds with the `shader-compiler` feature (libshaderc: ~20 minutes on 2 cores the first
# time, then cached in the target folder) and runs tests/committed_spirv.rs in its writing mode.
set -euo pipefail
cd "$(dirname "$0")/.."
source tools/env.sh
echo "[compile-shaders] shaders-glsl/ -> shaders-spv/ (target folder: $CARGO_TARGET_DIR)"
HYBRID_RT_BLESS_SPIRV=1 cargo test --locked --features shader-compiler --test committed_spirv \
  committed_spirv_is_what_the_glsl_compiles_to -- --exact --nocapture
git status --short shaders-spv/ || true
