#!/usr/bin/env bash
# Checks that Cargo.toml's rust-version is the real minimum (tools/test.sh runs it, so CI does),
# with every feature on (the shader compiler's code and dependencies count too).
#
# With one toolchain installed the minimum cannot be found by building with older ones, so
# tools/msrv.py derives it: the edition, the rust-version of every dependency in Cargo.lock's
# graph for this platform (`cargo metadata`), the language features the sources use, and the
# std items they use (clippy's incompatible_msrv lint, run here with the edition's first
# release as the MSRV so that it names every newer item and the release it is stable since).
# Fails when Cargo.toml's rust-version is below the derived minimum or the README's
# "Needs: Rust X+" line disagrees with it.
set -euo pipefail
cd "$(dirname "$0")/.."
source tools/env.sh

python3 tools/msrv.py --self-test

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

host=$(rustc -vV | sed -n 's/^host: //p')
cargo metadata --locked --all-features --format-version 1 --filter-platform "$host" >"$tmp/metadata.json"

if ! cargo clippy --version >/dev/null 2>&1; then
  echo "[msrv] FAILED: clippy is not installed (rustup component add clippy)"
  exit 1
fi
# The probe's MSRV: the edition's first release, given to clippy through a clippy.toml of its
# own (the package's, if it ever has one, plus the msrv line). The lint flags after `--` make
# this a clippy run of its own in cargo's cache, so a normal `cargo clippy` never replays it.
edition=$(python3 -c 'import json,sys; m=json.load(open(sys.argv[1])); print(next(p["edition"] for p in m["packages"] if p["id"]==m["resolve"]["root"]))' "$tmp/metadata.json")
floor=$(python3 -c 'import sys; sys.path.insert(0, "tools"); import msrv; print(msrv.show(msrv.EDITION_FLOOR[sys.argv[1]]))' "$edition")
{ grep -v '^\s*msrv' clippy.toml 2>/dev/null || true; echo "msrv = \"$floor\""; } >"$tmp/clippy.toml"
echo "[msrv] cargo clippy --all-targets with msrv = $floor (edition $edition), incompatible_msrv only"
CLIPPY_CONF_DIR="$tmp" cargo clippy --locked --all-targets --all-features --message-format=json \
  -- -A clippy::all -W clippy::incompatible_msrv >"$tmp/clippy.json"

python3 tools/msrv.py --metadata "$tmp/metadata.json" --clippy "$tmp/clippy.json" --root .
