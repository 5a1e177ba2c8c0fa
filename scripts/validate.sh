#!/usr/bin/env bash
# Runs every variant of every tetbench algorithm (not the VTK peers) under the Khronos Vulkan
# validation layer with synchronization validation on, and fails on any error or warning the
# layer reports, quoting the first ones (docs/gpu.md, "Validation"). wgpu's backend validation
# is on as well (WGPU_VALIDATION=1): wgpu asks for the same layer and logs what it reports;
# wgpu's own API validation is always on and fails the row.
#
# Two passes over small generated meshes (box:1k, shell:1k; 32² pixels, one frame, two
# viewpoints, no reference): the device as the adapter offers it, then the device requested
# with 4 KiB storage bindings (TETBENCH_MAX_STORAGE_BINDING), so that every chunked path
# (HAVS's and fragment PT's ChunkedBuffers, the ray caster's several mesh bindings, GATOR's
# chunked draws, the splatter's bricks) runs under the layer too, with timestamps off.
#
# Installs vulkan-validationlayers when no Khronos layer is found (set VK_ADD_LAYER_PATH to a
# directory holding VkLayer_khronos_validation.json to use another). Extra arguments go to
# both `tetbench run`s. Output: $TETBENCH_VALIDATE_OUT (default target-dir/validate/).
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/common.sh
ensure_prerequisites

start=$(date +%s)
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
    echo "tetbench: installing vulkan-validationlayers (the Khronos validation layer)" >&2
    apt_install vulkan-validationlayers
fi

target_dir="${CARGO_TARGET_DIR:-$PWD/target}"
out="${TETBENCH_VALIDATE_OUT:-$target_dir/validate}"
rm -rf "$out"
mkdir -p "$out"
out=$(cd "$out" && pwd)

# The layer's settings (VK_LAYER_SETTINGS_PATH): errors and warnings, every one of them (no
# per-message limit), written to one log file; synchronization validation on.
cat >"$out/vk_layer_settings.txt" <<EOF
khronos_validation.debug_action = VK_DBG_LAYER_ACTION_LOG_MSG
khronos_validation.log_filename = $out/layer.log
khronos_validation.report_flags = error,warn
khronos_validation.enable_message_limit = false
khronos_validation.enables = VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT
EOF

cargo build -q -p harness --bin tetbench
bin="$target_dir/debug/tetbench"

export VK_LAYER_SETTINGS_PATH="$out/vk_layer_settings.txt"
export VK_INSTANCE_LAYERS=VK_LAYER_KHRONOS_validation
export WGPU_VALIDATION=1
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"

# The loader's own report of the layers it inserts: proof that the layer ran (a layer that
# failed to load would otherwise pass silently with an empty log).
status=0
run_pass() {
    local name=$1
    shift
    echo "tetbench validate: pass $name" >&2
    VK_LOADER_DEBUG=layer "$@" "$bin" run --all-variants --datasets box:1k,shell:1k \
        --resolution 32 --viewpoints +x,+x+y+z --frames 1 --warmup 0 --rounds 1 \
        --no-reference --no-report --no-calibrate --out "$out/$name" "${extra[@]}" \
        >"$out/$name.log" 2>&1 || {
        status=1
        echo "tetbench validate: pass $name failed (tetbench run's output, last lines):" >&2
        grep -v -i 'loader' "$out/$name.log" | tail -n 20 >&2
    }
    if ! grep -q 'VK_LAYER_KHRONOS_validation' "$out/$name.log"; then
        echo "tetbench validate: the loader did not report loading VK_LAYER_KHRONOS_validation" \
            "in pass $name (see $out/$name.log); nothing was validated" >&2
        status=1
    fi
}
extra=("$@")
run_pass device env
run_pass chunked env TETBENCH_MAX_STORAGE_BINDING=4096 TETBENCH_TIMESTAMPS=off

rows=0
variants=0
for pass in device chunked; do
    csv="$out/$pass/results.csv"
    [ -f "$csv" ] || continue
    rows=$((rows + $(tail -n +2 "$csv" | wc -l)))
done
if [ -f "$out/device/results.csv" ]; then
    # Distinct algorithm + settings (columns named in the header).
    variants=$(python3 - "$out/device/results.csv" <<'EOF'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
print(len({(r["algorithm"], r["settings"]) for r in rows}))
EOF
)
fi

log="$out/layer.log"
touch "$log"
errors=$(grep -c -E 'Validation Error|^ERROR' "$log" || true)
warnings=$(grep -c -E 'Validation Warning|^WARNING' "$log" || true)
elapsed=$(($(date +%s) - start))
echo "tetbench validate: $rows rows ($variants variants × 2 data sets × 2 viewpoints, twice:" \
    "adapter limits, then 4 KiB bindings) under VK_LAYER_KHRONOS_validation with" \
    "synchronization validation: $errors errors, $warnings warnings, in ${elapsed} s"
if [ "$errors" -gt 0 ] || [ "$warnings" -gt 0 ]; then
    echo "tetbench validate: the layer reported problems; the first messages ($log):" >&2
    grep -E -A3 'Validation Error|Validation Warning|^ERROR|^WARNING' "$log" | head -n 40 >&2
    status=1
fi
exit $status
