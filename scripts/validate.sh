#!/usr/bin/env bash
# Runs every variant family of every tetbench algorithm (not the VTK peers) under the Khronos
# Vulkan validation layer with synchronization validation on, and fails on any error or warning
# the layer reports, quoting the first ones, or on any failed row (wgpu's own API validation is
# always on and fails the row). docs/gpu.md, "Validation", has the details and the timings.
#
# Pass "variants": `tetbench run --all-variants` on box:1k and shell:1k (32², one frame from
# +x+y+z, no reference): every combination of the settings that choose code paths (HAVS sort ×
# tags × mode × early termination, ray casting mode × table × et, splatting buckets × sort ×
# bricks × ese, fragment PT sort × shading, GATOR sort × cell model), the numeric knobs that
# only change constants at their extremes (HAVS k 2 and 16, ray casting 1×1 and 2×2 tiles,
# 4 and 32 peel layers and k 1 and 8, one splatting kernel and grid); HAVS in a pass of its own
# ("variants-havs"), since its k and the ray caster's share a key.
# Pass "chunked": the default variants (ray casting with its 2D table) on box:24k, the device
# requested with 256 KiB storage bindings, no timestamp queries and render passes of 4,096
# triangles (TETBENCH_MAX_STORAGE_BINDING, TETBENCH_TIMESTAMPS, TETBENCH_MAX_TRIANGLES_PER_PASS;
# as tests/device_limits.rs), so that every chunked and multi-pass path runs under the
# layer too.
#
# Installs vulkan-validationlayers when no Khronos layer is found (VK_ADD_LAYER_PATH may name a
# directory holding another VkLayer_khronos_validation.json). Output: $TETBENCH_VALIDATE_OUT
# (default TARGET_DIR/validate/): the layer's log, each pass's log and results.
#
# `--bin PATH` validates that tetbench binary instead of building a debug one (a release binary
# carried to a lent GPU's machine, which has no Rust: scripts/gpu.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/common.sh
bin=""
while [ $# -gt 0 ]; do
    case "$1" in
        --bin) bin=${2:?--bin needs a path}; shift ;;
        *) echo "scripts/validate.sh: unknown option $1 (only --bin PATH)" >&2; exit 2 ;;
    esac
    shift
done
if [ -n "$bin" ]; then
    [ -x "$bin" ] || { echo "scripts/validate.sh: no tetbench binary at $bin" >&2; exit 1; }
    bin=$(cd "$(dirname "$bin")" && pwd)/$(basename "$bin")
    ensure_vulkan_runtime
else
    ensure_prerequisites
fi

start=$SECONDS
layer_manifest=VkLayer_khronos_validation.json
have_validation_layer() {
    local d
    local IFS=:
    for d in ${VK_ADD_LAYER_PATH:-} ${VK_LAYER_PATH:-} /usr/share/vulkan/explicit_layer.d \
        /etc/vulkan/explicit_layer.d /usr/local/share/vulkan/explicit_layer.d; do
        [ -n "$d" ] && [ -e "$d/$layer_manifest" ] && return 0
    done
    return 1
}
if ! have_validation_layer; then
    echo "tetbench validate: installing vulkan-validationlayers (the Khronos validation layer)" >&2
    apt_install vulkan-validationlayers
fi

target_dir="${CARGO_TARGET_DIR:-$PWD/target}"
out="${TETBENCH_VALIDATE_OUT:-$target_dir/validate}"
rm -rf "$out"
mkdir -p "$out"
out=$(cd "$out" && pwd)

if [ -z "$bin" ]; then
    cargo build -q -p harness --bin tetbench
    bin="$target_dir/debug/tetbench"
fi

export VK_INSTANCE_LAYERS=VK_LAYER_KHRONOS_validation
# wgpu's backend validation: wgpu asks for the layer as well and adds its own checks.
export WGPU_VALIDATION=1
# No debug info in the SPIR-V: with it naga marks the source language as WGSL (SourceLanguage
# 10), which the SPIR-V validator inside Debian 12's layer (1.3.239) predates and reports as
# "Invalid source language operand: 10" for every shader. WGPU_DEBUG=1 shows it.
export WGPU_DEBUG="${WGPU_DEBUG:-0}"
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"

status=0
rows=0
common=(--resolution 32 --viewpoints +x+y+z --frames 1 --warmup 0 --rounds 1
    --no-reference --no-report --no-calibrate)
# `run_pass NAME [VAR=VALUE…] -- ARGS…`: one `tetbench run` under the layer.
run_pass() {
    local name=$1
    shift
    local vars=()
    while [ "$1" != -- ]; do
        vars+=("$1")
        shift
    done
    shift
    # The layer's settings (VK_LAYER_SETTINGS_PATH), one file and log per pass (the layer
    # truncates its log): every error, warning and information message, no per-message limit,
    # synchronization validation on. The information messages include the layer's status at
    # instance creation, the proof that it ran with these settings; only errors and warnings
    # count as failures.
    cat >"$out/$name.vk_layer_settings.txt" <<SETTINGS
khronos_validation.debug_action = VK_DBG_LAYER_ACTION_LOG_MSG
khronos_validation.log_filename = $out/$name.layer.log
khronos_validation.report_flags = error,warn,info
khronos_validation.enable_message_limit = false
khronos_validation.enables = VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT
SETTINGS
    local t0=$SECONDS
    env VK_LAYER_SETTINGS_PATH="$out/$name.vk_layer_settings.txt" "${vars[@]}" "$bin" run "${common[@]}" --out "$out/$name" "$@" >"$out/$name.log" 2>&1 || {
        status=1
        echo "tetbench validate: pass $name failed ($out/$name.log): $(grep -c FAILED "$out/$name.log" || true) failed rows; the first:" >&2
        # The first failed row and its cause, then tetbench's closing error line.
        awk '/FAILED/ && !f { f = 1; n = 0 } f && n++ < 8' "$out/$name.log" >&2 || true
        grep -E '^error' "$out/$name.log" | cut -c1-300 >&2 || true
    }
    # Rows and distinct variants (algorithm + settings) of the pass's results.
    local counts
    counts=$(python3 - "$out/$name/results.csv" <<'PY' 2>/dev/null || echo "0 0"
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1], newline="")))
print(len(rows), len({(r["algorithm"], r["settings"]) for r in rows}))
PY
)
    rows=$((rows + ${counts% *}))
    echo "tetbench validate: pass $name: ${counts% *} rows, ${counts#* } variants, $((SECONDS - t0)) s" >&2
}
# HAVS's k and the ray caster's k (passes between counts) share a key, so each gets its own pass.
run_pass variants -- --all-variants --datasets box:1k,shell:1k \
    --algorithms gator-pt,fragment-pt,raycast,splat \
    --settings 'tiles=1x1|2x2;layers=4|32;radius=2;slab=1;grid=32'
run_pass variants-havs -- --all-variants --datasets box:1k,shell:1k --algorithms havs \
    --settings 'k=2|16'
run_pass chunked TETBENCH_MAX_STORAGE_BINDING=262144 TETBENCH_TIMESTAMPS=off TETBENCH_MAX_TRIANGLES_PER_PASS=4096 -- \
    --datasets box:24k --settings table=2d

log="$out/layer.log"
cat "$out"/*.layer.log >"$log" 2>/dev/null || true
# The layer's status line, written once per instance: without it the layer did not run (a
# layer that failed to load would otherwise pass with an empty log).
instances=$(grep -c 'Khronos Validation Layer Active' "$log" || true)
if [ "$instances" -lt 2 ] || ! grep -q 'Current Enables:.*SYNCHRONIZATION_VALIDATION' "$log"; then
    echo "tetbench validate: the layer's status line (with synchronization validation) is" \
        "missing from $log: VK_LAYER_KHRONOS_validation did not run; nothing was validated" >&2
    status=1
fi
errors=$(grep -c 'Validation Error' "$log" || true)
warnings=$(grep -c -E 'Validation (Warning|Performance Warning)' "$log" || true)
echo "tetbench validate: $rows rows under VK_LAYER_KHRONOS_validation with synchronization" \
    "validation ($instances instances): $errors errors, $warnings warnings; $((SECONDS - start)) s"
if [ "$errors" -gt 0 ] || [ "$warnings" -gt 0 ]; then
    echo "tetbench validate: the layer reported problems; the first distinct ones ($log):" >&2
    # Object handles differ between repeats of one message: fold them before keeping 5.
    grep -E 'Validation (Error|Warning|Performance Warning)' "$log" |
        sed 's/handle = 0x[0-9a-f]*/handle = …/g' | awk '!seen[$0]++ && n++ < 5' |
        cut -c1-600 >&2 || true
    status=1
fi
exit $status
