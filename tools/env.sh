# Sourced by the tools/ scripts: where cargo builds.
#
# The target folder lives outside the checkout by default, so a fresh clone on a machine that
# built hybrid-rt before reuses what it compiled, libshaderc above all (the test command's
# `shader-compiler` feature builds it from source: ~20 minutes on 2 cores). Override with
# CARGO_TARGET_DIR.
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$HOME/.cache/hybrid-rt/target}"
# Everything uses cargo's dev profile, which Cargo.toml tunes for speed (dependencies at
# opt-level 3): one libshaderc build serves the build script, the binary and the tests.
