#!/usr/bin/env bash
# Profiles the frames of each algorithm with `perf record -e cpu-clock` (software clock samples:
# no hardware counters needed, so it works on a VM and in CI) and writes docs-ready summaries.
#
#   scripts/profile.sh [--bin BIN] [--out DIR] [--algorithms LIST] [--datasets LIST]
#                      [--resolutions LIST] [--frames N] [--viewpoint VP]
#
# For every algorithm × data set × resolution it runs `tetbench run` for one viewpoint under
# `perf record -D -1 --control fifo:…`: sampling starts only once the variants are prepared
# (the run loop enables it through TETBENCH_PERF_CONTROL, harness/src/run/perf_control.rs), so
# loading and pipeline compilation stay out of the profile. `scripts/profile_summary.py` then
# sorts every sample into host work of ours, wgpu and the driver's submission path, llvmpipe's
# vertex/setup and rasterisation/fragment work (JIT code included), the harness's per-row work,
# and the rest, and writes DIR/profile.md. Off-CPU time (waits) is not sampled: the results'
# frame times give it (total − CPU). Defaults: the five algorithms' default variants, box:20k and
# box:1m, 128² and 512², 10 timed frames.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/common.sh

bin=""
out="out/profile"
algorithms="gator-pt,havs,fragment-pt,raycast,splat"
datasets="box:20k,box:1m"
resolutions="128,512"
frames=10
viewpoint="+x+y+z"
while [ $# -gt 0 ]; do
  case "$1" in
    --bin) bin="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    --algorithms) algorithms="$2"; shift 2 ;;
    --datasets) datasets="$2"; shift 2 ;;
    --resolutions) resolutions="$2"; shift 2 ;;
    --frames) frames="$2"; shift 2 ;;
    --viewpoint) viewpoint="$2"; shift 2 ;;
    -h|--help) sed -n '2,16p' "$0"; exit 0 ;;
    *) echo "profile.sh: unknown option $1 (see --help)" >&2; exit 1 ;;
  esac
done

if ! command -v perf >/dev/null; then
  echo "profile.sh: perf is missing (Debian: apt-get install linux-perf)" >&2
  exit 1
fi
if [ -z "$bin" ]; then
  ensure_prerequisites
  cargo build --release -p harness --bin tetbench
  bin="$(tetbench_release_bin)"
fi
mkdir -p "$out"
fifo_dir="$(mktemp -d)"
trap 'rm -rf "$fifo_dir"' EXIT
mkfifo "$fifo_dir/ctl" "$fifo_dir/ack"

IFS=',' read -r -a algs <<<"$algorithms"
IFS=',' read -r -a sets <<<"$datasets"
IFS=',' read -r -a sizes <<<"$resolutions"
for d in "${sets[@]}"; do
  for r in "${sizes[@]}"; do
    for a in "${algs[@]}"; do
      name="${a}__$(echo "$d" | tr ':/' '__')__${r}"
      echo "profile.sh: $name" >&2
      # Fill the reference cache first, so the profiled run's rows only read it back (the
      # reference is rendered once per view and mesh, not per variant; it is not frame work).
      "$bin" run --algorithms "$a" --datasets "$d" --viewpoints "$viewpoint" --resolution "$r" \
        --frames 1 --warmup 0 --no-calibrate --no-report --out "$out/$name.warm" >/dev/null 2>&1 || true
      rm -rf "$out/$name.warm"
      TETBENCH_PERF_CONTROL="$fifo_dir/ctl,$fifo_dir/ack" \
        perf record -q -e cpu-clock -F 1999 -D -1 --control "fifo:$fifo_dir/ctl,$fifo_dir/ack" \
        -o "$out/$name.perf.data" -- \
        "$bin" run --algorithms "$a" --datasets "$d" --viewpoints "$viewpoint" \
        --resolution "$r" --frames "$frames" --warmup 2 --no-calibrate --no-report \
        --out "$out/$name.run" >"$out/$name.log" 2>&1 \
        || { echo "profile.sh: $name failed (see $out/$name.log)" >&2; continue; }
      perf report -q -i "$out/$name.perf.data" --stdio --no-children \
        -F sample,comm,dso,sym -t '|' >"$out/$name.report.txt" 2>/dev/null
      rm -f "$out/$name.perf.data"
    done
  done
done
python3 scripts/profile_summary.py "$out"
echo "profile.sh: wrote $out/profile.md" >&2
