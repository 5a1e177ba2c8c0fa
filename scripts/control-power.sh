#!/usr/bin/env bash
# How `tetbench compare` judges time against the control measured beside the rows
# (docs/regression.md, "The machine and the code"). Builds HEAD twice in release — as it is
# (BASE) and with a scratch change in render-core that busy-waits 40 % of every frame's own
# time before its clock stops (SPIN: every algorithm ×1.4, the machine unchanged) — then, per
# trial:
#   A      BASE on the idle machine;
#   BUSY   BASE again, with two busy loops beside it (the machine ×~2, the code unchanged);
#   SPIN   SPIN on the idle machine;
# and prints `compare A BUSY --fail-on regression` (want exit 0: the machine) and
# `compare A SPIN --fail-on regression` (want exit 3, named common to every algorithm), one
# line per trial, then the totals. The patch lives only in a temporary worktree: it is never
# committed.
#
#   scripts/control-power.sh [TRIALS]        # default 10
#
# Environment: CONTROL_POWER_BASE and CONTROL_POWER_SPIN (binaries built already, BASE of HEAD and
# SPIN of HEAD with the patch below: then nothing is built), CONTROL_POWER_WORK (default
# target/control-power), CONTROL_POWER_SEED (a release
# target directory to copy before the first build, so that the dependencies are not built
# again; default target/release when it exists), CONTROL_POWER_MATRIX (the
# run options; default three algorithms on box:10k, 3 viewpoints, 128 px, 3 rounds of 1 frame
# after 1 warm-up, without the reference), CONTROL_POWER_LOAD (the command run twice beside
# BUSY; default a shell busy loop).
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/common.sh
ensure_prerequisites

trials=${1:-10}
work=$(realpath -m "${CONTROL_POWER_WORK:-target/control-power}")
src="$work/src"
target="$work/target"
matrix=${CONTROL_POWER_MATRIX:---datasets box:10k --viewpoints +x,+x+y+z,-x+y-z --resolution 128 --algorithms gator-pt,havs,raycast --rounds 3 --frames 1 --warmup 1 --no-reference}
seed=${CONTROL_POWER_SEED:-target/release}
load=${CONTROL_POWER_LOAD:-while :; do :; done}
head=$(git rev-parse HEAD)
mkdir -p "$work/bin" "$work/trials"

prepare_src() {
    if [ -e "$src/.git" ]; then
        git -C "$src" checkout --quiet --force --detach "$head"
    else
        git worktree add --quiet --detach "$src" "$head"
    fi
    # -a keeps the times cargo's fingerprints compare, so the dependencies are not rebuilt.
    if [ ! -d "$target/release" ] && [ -d "$seed" ]; then
        mkdir -p "$target" && cp -a "$seed" "$target/release"
    fi
}
build() {
    (cd "$src" && CARGO_TARGET_DIR="$target" cargo build --release -q -p harness --bin tetbench)
    cp "$target/release/tetbench" "$1"
}
stamp="$work/bin/.built-$head"
if [ -n "${CONTROL_POWER_BASE:-}" ] && [ -n "${CONTROL_POWER_SPIN:-}" ]; then
    cp "$CONTROL_POWER_BASE" "$work/bin/base"
    cp "$CONTROL_POWER_SPIN" "$work/bin/spin"
    touch "$stamp"
fi
if [ ! -e "$stamp" ]; then
    prepare_src
    echo "control-power: building BASE ($head)" >&2
    build "$work/bin/base"
    python3 - "$src/renderers/core/src/frame.rs" <<'EOF'
import sys
path = sys.argv[1]
text = open(path).read()
anchor = "    pub fn finish(mut self) -> FrameTimes {\n"
if anchor not in text:
    sys.exit(f"control-power: {path} no longer has the line the scratch spin patches")
text = text.replace(anchor, anchor + """        // SCRATCH (scripts/control-power.sh, never committed): 40 % more of every frame.
        let spin = self.started.elapsed().mul_f64(0.4);
        let t0 = Instant::now();
        while t0.elapsed() < spin {
            std::hint::spin_loop();
        }
""")
open(path, "w").write(text)
EOF
    echo "control-power: building SPIN" >&2
    build "$work/bin/spin"
    git -C "$src" checkout --quiet --force --detach "$head"
    touch "$stamp"
fi

run() { # BINARY OUT
    rm -rf "$2"
    # shellcheck disable=SC2086
    "$1" run $matrix --no-report --out "$2" >"$2.log" 2>&1
}
busy_pids=()
start_load() {
    for _ in 1 2; do
        bash -c "$load" &
        busy_pids+=($!)
    done
}
stop_load() {
    kill "${busy_pids[@]}" 2>/dev/null || true
    wait "${busy_pids[@]}" 2>/dev/null || true
    busy_pids=()
}
trap stop_load EXIT

judge() { # BASE NEW → "exit CODE machine ×M run-wide ×R [common]"
    local code=0 out
    out=$("$work/bin/base" compare "$1" "$2" --fail-on regression --out "$2/compare" 2>&1) || code=$?
    local machine runwide common=""
    machine=$(grep -o 'machine drift: ×[0-9.]*' <<<"$out" | head -1 | sed 's/.*×//')
    runwide=$(grep -o 'What remains run-wide: ×[0-9.]*' <<<"$out" | head -1 | sed 's/.*×//')
    grep -q 'common to every algorithm' <<<"$out" && common=" common"
    echo "exit $code machine ×${machine:--} run-wide ×${runwide:--}$common"
}

busy_ok=0
spin_ok=0
echo "trial | A vs BUSY (want exit 0) | A vs SPIN (want exit 3, common) | load average"
for i in $(seq 1 "$trials"); do
    d="$work/trials/$i"
    mkdir -p "$d"
    run "$work/bin/base" "$d/a"
    start_load
    run "$work/bin/base" "$d/busy"
    stop_load
    run "$work/bin/spin" "$d/spin"
    b=$(judge "$d/a" "$d/busy")
    s=$(judge "$d/a" "$d/spin")
    [[ $b == "exit 0 "* ]] && busy_ok=$((busy_ok + 1))
    [[ $s == "exit 3 "*common ]] && spin_ok=$((spin_ok + 1))
    echo "$i | $b | $s | $(cut -d' ' -f1-3 /proc/loadavg)"
done
echo "BUSY judged the machine (exit 0): $busy_ok of $trials"
echo "SPIN judged a regression common to every algorithm (exit 3): $spin_ok of $trials"
