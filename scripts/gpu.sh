#!/usr/bin/env bash
# One command for the minutes a machine with a GPU is lent (docs/gpu.md): builds tetbench in
# release (or takes --bin), refuses a software adapter (lavapipe, llvmpipe, SwiftShader, WARP)
# unless --allow-software, then runs, timing each step:
#
#   calibrate   tetbench calibrate --force                     → calibration.json
#   suite       the default suite with --rounds 5               → results.json, results.csv, samples.csv
#   reproduce   tetbench reproduce PAPER --quick --rounds 5 per paper → reproduce/
#   validate    scripts/validate.sh under the Khronos layer, with --validate → validation.txt
#   peers       the default suite of VTK's mappers, when VTK is installed → peers/
#   scale       every algorithm's default variants on box:1m, box:5m, box:20m and spx2 at
#               512² and 1024², one viewpoint (+x+y+z), --rounds rounds → scale/RES/ (with its
#               report and charts) and a table in gpu.md; on a software adapter box:1k and
#               box:2k at 32² and 64² instead (a smoke test that runs in CI time)
#   floor       the per-frame floor (`tetbench calibrate --floor`: submit, wait, the clear of an
#               empty mesh's frame, readbacks, timestamps) at each scale resolution, and every
#               algorithm's default variants on a tiny mesh (box:5, one cell) → floor/ and
#               gpu.md, beside the scale rows (never subtracted from them)
#
# into ONE directory, reports/baselines/ADAPTER-DATE/ (the shape of scripts/baseline.sh's:
# ready to commit, `tetbench compare` and `history` read it as a baseline), with gpu.md: the
# adapter, the command, and the wall time of every step. Needs no network once built (VTK is
# used only when already installed). Options shrink it:
#
#   --allow-software   run on a software adapter too (a smoke test of this script)
#   --rounds N         rounds of the suite (default 5)
#   --quick            skip the papers' reproduction
#   --papers LIST      reproduce only these papers (comma-separated: havs, gator, fragment-pt,
#                      raycast, splat; default all)
#   --skip-peers       skip the VTK peers
#   --validate         also run scripts/validate.sh with this binary (needs the Khronos layer:
#                      installed, or VK_ADD_LAYER_PATH naming its manifest's folder)
#   --out DIR          output directory (default reports/baselines/ADAPTER-DATE)
#   --bin PATH         use this tetbench binary instead of building one
#   --skip-suite       skip the default suite (with --quick and --skip-peers: only the scale
#                      and floor steps, as tests/gpu_script.rs runs it)
#   --skip-scale       skip the scale and floor steps
#   -- ARGS            passed to the suite's `tetbench run` (e.g. -- --datasets box:1k)
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/common.sh

orig_args=("$@")
allow_software=0
rounds=5
papers=all
skip_peers=0
validate=0
out=""
bin=""
suite_args=()
skip_suite=0
skip_scale=0
while [ $# -gt 0 ]; do
    case "$1" in
        --allow-software) allow_software=1 ;;
        --rounds) rounds=${2:?--rounds needs a number}; shift ;;
        --quick) papers="" ;;
        --papers) papers=${2:?--papers needs a list}; shift ;;
        --skip-peers) skip_peers=1 ;;
        --validate) validate=1 ;;
        --out) out=${2:?--out needs a directory}; shift ;;
        --bin) bin=${2:?--bin needs a path}; shift ;;
        --) shift; suite_args=("$@"); break ;;
        --skip-suite) skip_suite=1 ;;
        --skip-scale) skip_scale=1 ;;
        -h|--help) sed -n '2,38p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
        *) echo "scripts/gpu.sh: unknown option $1 (see --help)" >&2; exit 2 ;;
    esac
    shift
done
case "$rounds" in ''|*[!0-9]*|0) echo "scripts/gpu.sh: --rounds $rounds: need a whole number ≥ 1" >&2; exit 2 ;; esac

# A given binary needs no Rust (the GPU machine may have none), only Vulkan.
if [ -n "$bin" ]; then ensure_vulkan_runtime; else ensure_prerequisites; fi
script_start=$(date +%s)
timings=()
# `step NAME CMD…`: runs CMD, records and prints its wall time; a failing step is recorded and
# the script goes on (a lent GPU's minutes are better spent on the other steps), then fails.
failed=()
step() {
    local name=$1
    shift
    local t0
    t0=$(date +%s%N)
    echo "=== gpu.sh: $name" >&2
    local rc=0
    "$@" || rc=$?
    local ms=$((($(date +%s%N) - t0) / 1000000))
    local s
    s=$(printf '%d.%d' $((ms / 1000)) $((ms % 1000 / 100)))
    if [ "$rc" -ne 0 ]; then
        failed+=("$name (exit $rc)")
        timings+=("| $name | $s | failed (exit $rc) |")
    else
        timings+=("| $name | $s | ok |")
    fi
    echo "=== gpu.sh: $name: $s s$([ "$rc" -ne 0 ] && echo ", FAILED (exit $rc)")" >&2
}

if [ -z "$bin" ]; then
    build() { cargo build --release -p harness --bin tetbench; }
    step build build
    bin="${CARGO_TARGET_DIR:-$PWD/target}/release/tetbench"
fi
[ -x "$bin" ] || { echo "scripts/gpu.sh: no tetbench binary at $bin" >&2; exit 1; }

# The adapter, from a calibration measured now (also the first step of the work).
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cache="${TETBENCH_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/tetbench}"
calibrate() { "$bin" calibrate --force --json --cache-dir "$cache" >"$tmp/calibration.json"; }
step calibrate calibrate
[ -s "$tmp/calibration.json" ] || { echo "scripts/gpu.sh: calibration failed; no adapter" >&2; exit 1; }
adapter=$(grep -m1 '"adapter"' "$tmp/calibration.json" | sed 's/.*"adapter": *"\(.*\)",*$/\1/')
software=$(printf '%s' "$adapter" | grep -o -i -E 'llvmpipe|lavapipe|softpipe|swiftshader|microsoft basic render' | head -n1 || true)
if [ -n "$software" ]; then
    if [ "$allow_software" -eq 0 ]; then
        echo "scripts/gpu.sh: the adapter is \"$adapter\", a software renderer ($software):" \
            "its times say nothing about a GPU. Is the GPU's Vulkan driver installed" \
            "(e.g. NVIDIA's libnvidia-gl / nvidia-vulkan-icd; ls /usr/share/vulkan/icd.d)?" \
            "Pass --allow-software to run anyway." >&2
        exit 1
    fi
    echo "=== gpu.sh: adapter \"$adapter\" is a software renderer ($software); going on (--allow-software)" >&2
else
    echo "=== gpu.sh: adapter \"$adapter\"" >&2
fi

slug=$(printf '%s' "$adapter" | tr 'A-Z' 'a-z' | sed 's/[^a-z0-9]\{1,\}/-/g; s/^-//; s/-$//')
dest="${out:-reports/baselines/$slug-$(date -u +%Y-%m-%d)}"
rm -rf "$dest"
mkdir -p "$dest"
cp "$tmp/calibration.json" "$dest/calibration.json"

# The baseline: the default suite, no report (the files scripts/baseline.sh stores).
suite() {
    "$bin" run --rounds "$rounds" --out "$tmp/suite" --no-report --cache-dir "$cache" \
        "${suite_args[@]}" &&
        cp "$tmp/suite/results.json" "$tmp/suite/results.csv" "$tmp/suite/samples.csv" "$dest/"
}
if [ "$skip_suite" -eq 0 ]; then step suite suite; else echo "=== gpu.sh: suite skipped (--skip-suite)" >&2; fi

if [ -n "$papers" ]; then
    if [ "$papers" = all ]; then
        # Five rounds a side, so the timing claims are decided (one frame a side never is).
        reproduce() { "$bin" reproduce all --quick --rounds 5 --out "$dest/reproduce" --cache-dir "$cache"; }
        step "reproduce all --quick --rounds 5" reproduce
    else
        IFS=, read -r -a paper_list <<<"$papers"
        for p in "${paper_list[@]}"; do
            reproduce_one() { "$bin" reproduce "$1" --quick --rounds 5 --out "$dest/reproduce" --cache-dir "$cache"; }
            step "reproduce $p --quick --rounds 5" reproduce_one "$p"
        done
    fi
    # Images are regenerated by the command; only the reports and tables are kept.
    find "$dest/reproduce" -type d -name images -prune -exec rm -rf {} + 2>/dev/null || true
fi

if [ "$validate" -eq 1 ]; then
    # The whole output of the script: each pass's rows and seconds, then the layer's count of
    # errors and warnings (and the first distinct ones when there are any).
    validate_run() { TETBENCH_VALIDATE_OUT="$tmp/validate" scripts/validate.sh --bin "$bin" >"$dest/validation.txt" 2>&1; }
    step validate validate_run
fi

vtk_python="${TETBENCH_VTK_PYTHON:-$PWD/.venv-vtk/bin/python}"
if [ "$skip_peers" -eq 1 ]; then
    echo "=== gpu.sh: peers skipped (--skip-peers)" >&2
elif "$vtk_python" -c 'import vtkmodules.vtkRenderingVolume' >/dev/null 2>&1; then
    peers() {
        TETBENCH_VTK_PYTHON="$vtk_python" "$bin" run --algorithms vtk-pt,vtk-raycast,vtk-zsweep \
            --rounds "$rounds" --out "$tmp/peers" --no-report --no-calibrate \
            --cache-dir "$cache" "${suite_args[@]}" &&
            mkdir -p "$dest/peers" &&
            cp "$tmp/peers/results.json" "$tmp/peers/results.csv" "$tmp/peers/samples.csv" "$dest/peers/"
    }
    step peers peers
else
    echo "=== gpu.sh: peers skipped: no Python with VTK at $vtk_python (scripts/setup-vtk.sh installs it; needs the network)" >&2
fi

# Scale and floor (issue 43): the algorithms on meshes large enough that a GPU's frame is the
# algorithm's work, and beside them what a frame costs with no work at all.
if [ "$skip_scale" -eq 0 ]; then
    if [ -n "$software" ]; then
        # A software adapter: the same step at sizes that run in CI time.
        scale_datasets=box:1k,box:2k
        scale_resolutions="32 64"
        tiny_frames=2
    else
        scale_datasets=box:1m,box:5m,box:20m,spx2
        scale_resolutions="512 1024"
        tiny_frames=10
    fi
    mkdir -p "$dest/scale" "$dest/floor"
    scale_one() {
        "$bin" run --datasets "$scale_datasets" --resolution "$1" --viewpoints +x+y+z \
            --rounds "$rounds" --frames 1 --warmup 1 --no-reference --out "$dest/scale/$1" \
            --cache-dir "$cache"
    }
    floor_one() {
        "$bin" calibrate --floor --json --resolution "$1" >"$dest/floor/floor-$1.json" &&
            "$bin" calibrate --floor --resolution "$1" >"$dest/floor/floor-$1.md" &&
            "$bin" run --datasets box:5 --resolution "$1" --viewpoints +x+y+z --rounds "$rounds" \
                --frames "$tiny_frames" --warmup 1 --no-reference --no-report \
                --out "$dest/floor/tiny-$1" --cache-dir "$cache"
    }
    for res in $scale_resolutions; do
        step "scale $res" scale_one "$res"
        step "floor $res" floor_one "$res"
    done
    # Rendered images are regenerated by the command; the rows, samples and report stay.
    find "$dest/scale" "$dest/floor" -type d -name images -prune -exec rm -rf {} + 2>/dev/null || true
fi

# `scale_tables DEST`: gpu.md's scale and floor sections, from the runs' results.csv and the
# floor files (scripts/scale_tables.py; without Python, where the files are).
scale_tables() {
    if command -v python3 >/dev/null 2>&1; then
        python3 scripts/scale_tables.py "$1"
    else
        echo "## Scale and per-frame floor"
        echo
        echo "No python3 here to tabulate them: see scale/*/results.csv, floor/floor-*.md and floor/tiny-*/results.csv."
    fi
}

total=$(($(date +%s) - script_start))
{
    echo "# scripts/gpu.sh on $adapter"
    echo
    echo "- adapter: $adapter${software:+ (software: $software)}"
    echo "- date (UTC): $(date -u +%Y-%m-%dT%H:%M:%SZ)"
    # The commit the binary was built from (its rows record it), not the checkout's: a carried
    # binary may run in a copy of the tree without .git.
    first_results=$(ls "$dest/results.json" "$dest"/scale/*/results.json 2>/dev/null | head -n1 || true)
    commit=$(grep -m1 -o '"git_commit": *"[0-9a-f]*"' "${first_results:-/dev/null}" 2>/dev/null | grep -o '[0-9a-f]\{40\}' || true)
    dirty=$(grep -m1 -o '"git_dirty": *[a-z]*' "${first_results:-/dev/null}" 2>/dev/null | grep -o '[a-z]*$' || true)
    echo "- commit: ${commit:-unknown (no results.json)}$([ "$dirty" = true ] && echo ' (built with uncommitted changes)')"
    echo "- command: scripts/gpu.sh ${orig_args[*]:-}"
    echo "- options: rounds $rounds; papers ${papers:-none}; validation $([ "$validate" -eq 1 ] && echo yes || echo no); peers $([ "$skip_peers" -eq 1 ] && echo skipped || echo 'when VTK is installed')"
    echo
    echo "| step | seconds | |"
    echo "|---|---:|---|"
    printf '%s\n' "${timings[@]}"
    echo "| total | $total | |"
    if [ "$skip_scale" -eq 0 ]; then
        echo
        scale_tables "$dest"
    fi
} >"$dest/gpu.md"
echo >&2
cat "$dest/gpu.md" >&2
echo "=== gpu.sh: everything in $dest ($total s)" >&2
if [ "${#failed[@]}" -gt 0 ]; then
    echo "=== gpu.sh: failed steps: ${failed[*]}" >&2
    exit 1
fi
