#!/usr/bin/env bash
# Runs the default suite in a release build and stores it as a committed baseline:
# reports/baselines/<adapter>-<YYYY-MM-DD>/ with results.json (samples, image hashes and the
# backend's calibration in machine.calibration), results.csv, samples.csv and calibration.json.
# The suite runs with --rounds 5 (docs/regression.md, "Rounds are the samples").
# No images (the hashes in the rows still show any changed pixel). Extra arguments go to
# `tetbench run` (e.g. --cache-dir DIR). Replaces a baseline of the same adapter and day.
set -euo pipefail
cd "$(dirname "$0")/.."
# A baseline says which commit it measured; with uncommitted changes to tracked files it would
# not be that commit (the binary records the dirty flag at build time; compare warns on it).
if [ -n "$(git status --porcelain --untracked-files=no)" ]; then
    echo "baseline.sh: the working tree has uncommitted changes; commit or stash them first:" >&2
    git status --short --untracked-files=no >&2
    exit 1
fi
. scripts/common.sh
ensure_prerequisites
cargo build --release -p harness --bin tetbench
bin=$(tetbench_release_bin)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$bin" run --rounds 5 --out "$tmp/run" --no-report "$@"
# The adapter's name is the first "name" of results.json (machine.adapter.name).
adapter=$(grep -m1 '"name"' "$tmp/run/results.json" | sed 's/.*"name": *"\(.*\)",*$/\1/')
slug=$(printf '%s' "$adapter" | tr 'A-Z' 'a-z' | sed 's/[^a-z0-9]\{1,\}/-/g; s/^-//; s/-$//')
dest="reports/baselines/$slug-$(date -u +%Y-%m-%d)"
rm -rf "$dest"
mkdir -p "$dest"
cp "$tmp/run/results.json" "$tmp/run/results.csv" "$tmp/run/samples.csv" "$dest/"
"$bin" calibrate --json "$@" > "$dest/calibration.json" 2>/dev/null ||
    "$bin" calibrate --json > "$dest/calibration.json"
echo "baseline stored in $dest"
