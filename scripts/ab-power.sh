#!/usr/bin/env bash
# The power of `tetbench ab` on this machine (issue 25; docs/regression.md, "A/B power"):
# builds HEAD twice in release — as it is (BASE) and with a scratch slowdown of one algorithm
# (NEW: after every timed frame of that algorithm a busy-wait of (factor − 1) × the frame's
# own time, added to the frame's total_ms; the factor comes from TETBENCH_SCRATCH_SLOWDOWN at
# run time, so one build serves every factor) — then runs trials of `tetbench ab`, rotating
# through same-build pairs (BASE against a copy of itself) and each factor, and prints the
# share of trials that found the slowdown and those with a false call. The patch lives only in
# a temporary worktree: it is never committed.
#
#   scripts/ab-power.sh [TRIALS]          # default 10 trials per row
#
# Environment: AB_POWER_WORK (default target/ab-power: worktree, target, binaries, trials),
# AB_POWER_FACTORS (default "1.05 1.10 1.25 1.5"), AB_POWER_ALGORITHM (gator-pt),
# AB_POWER_PAIRS (5), AB_POWER_THRESHOLDS ("1.10 1.05": `ab` runs with the first, compare
# --paired judges the same rounds again with the others), AB_POWER_MATRIX (the run options; default the
# default suite's box:10k, 3 viewpoints, 128 px, without splat — a second per frame on
# lavapipe, half of each round — 2 frames after 1 warm-up, without the reference and the
# calibration), AB_POWER_TARGET_DIR, AB_POWER_SRC,
# AB_POWER_DEADLINE (a `date -d` time: no trial starts after it).
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/common.sh
ensure_prerequisites

trials=${1:-10}
root=$PWD
work=$(realpath -m "${AB_POWER_WORK:-target/ab-power}")
src=$(realpath -m "${AB_POWER_SRC:-$work/src}")
target=$(realpath -m "${AB_POWER_TARGET_DIR:-$work/target}")
factors=${AB_POWER_FACTORS:-1.05 1.10 1.25 1.5}
algorithm=${AB_POWER_ALGORITHM:-gator-pt}
pairs=${AB_POWER_PAIRS:-5}
thresholds=${AB_POWER_THRESHOLDS:-1.10 1.05}
matrix=${AB_POWER_MATRIX:---datasets box:10k --viewpoints +x,+x+y+z,-x+y-z --resolution 128 --algorithms gator-pt,havs,fragment-pt,raycast --frames 2 --warmup 1 --no-reference --no-calibrate}
deadline=${AB_POWER_DEADLINE:+$(date -d "$AB_POWER_DEADLINE" +%s)}
head=$(git rev-parse HEAD)
mkdir -p "$work/bin" "$work/trials"

if [ -e "$src/.git" ]; then
    git -C "$src" checkout --quiet --force --detach "$head"
else
    git worktree add --quiet --detach "$src" "$head"
fi
build() {
    (cd "$src" && CARGO_TARGET_DIR="$target" cargo build --release -q -p harness --bin tetbench)
    cp "$target/release/tetbench" "$1"
}
stamp="$work/bin/.built-$head"
if [ -e "$stamp" ]; then
    echo "ab-power: BASE and NEW of $head already built in $work/bin" >&2
else
echo "ab-power: building BASE ($head) in $src" >&2
build "$work/bin/base"
cp "$work/bin/base" "$work/bin/base-copy"

# The scratch slowdown: a busy-wait after each timed frame of the algorithm.
python3 - "$src/harness/src/run/measure.rs" <<'EOF'
import sys
path = sys.argv[1]
text = open(path).read()
anchor = 'frames.push(guarded("render", || renderer.render(self.gpu, &camera))?);'
if anchor not in text:
    sys.exit(f"ab-power: {path} no longer has the line the scratch slowdown patches: {anchor}")
text = text.replace(anchor, '''let mut frame = guarded("render", || renderer.render(self.gpu, &camera))?;
            scratch_slowdown(renderer.algorithm(), &mut frame);
            frames.push(frame);''')
text += '''
/// SCRATCH (scripts/ab-power.sh, never committed): TETBENCH_SCRATCH_SLOWDOWN=ALG=FACTOR makes
/// ALG's frames FACTOR times slower by busy-waiting after each one.
fn scratch_slowdown(algorithm: &str, frame: &mut FrameStats) {
    let Ok(spec) = std::env::var("TETBENCH_SCRATCH_SLOWDOWN") else { return };
    let Some((alg, factor)) = spec.split_once('=') else { return };
    let factor: f64 = factor.parse().expect("TETBENCH_SCRATCH_SLOWDOWN=ALG=FACTOR");
    if alg != algorithm || factor <= 1.0 {
        return;
    }
    let wait = std::time::Duration::from_secs_f64(frame.total_ms * (factor - 1.0) * 1e-3);
    let start = std::time::Instant::now();
    while start.elapsed() < wait {
        std::hint::spin_loop();
    }
    frame.total_ms += start.elapsed().as_secs_f64() * 1e3;
}
'''
open(path, "w").write(text)
EOF
echo "ab-power: building NEW (HEAD + scratch slowdown of $algorithm)" >&2
build "$work/bin/slow"
git -C "$src" checkout --quiet --force "$head"
touch "$stamp"
fi

csv="$work/trials.csv"
[ -e "$csv" ] || echo "trial,factor,threshold,exit,found,false_calls,run_factor,seconds,load_start,utc" >"$csv"
# What a compare.json says about the slowdown: one CSV line.
verdict() {
    python3 - "$@" >>"$csv" <<'EOF'
import json, sys, datetime
path, alg, n, factor, threshold, status, seconds, load = sys.argv[1:]
try:
    c = json.load(open(path))
    regs = c["regressions"]
    run_factor = c.get("run_factor") or ""
except (OSError, ValueError):
    regs, run_factor = None, ""
if regs is None:
    found, false = "error", "error"
else:
    # Findings are objects since issue 44 (their `text` is the old sentence).
    found = sum(r["text"].startswith(f"slower: {alg} ") for r in regs)
    false = len(regs) - found
now = datetime.datetime.now(datetime.timezone.utc).strftime("%H:%M:%S")
print(f"{n},{factor},{threshold},{status},{found},{false},{run_factor},{seconds},{load},{now}")
EOF
    tail -n 1 "$csv" >&2
}
# One trial: `ab` into its own folder at the first threshold; the other thresholds judge the
# same merged rounds again with `compare` (the same samples, another threshold).
trial() {
    local n=$1 factor=$2 out new env_factor first rest t
    out="$work/trials/$n-$factor"
    rm -rf "$out"
    if [ "$factor" = same ]; then
        new="$work/bin/base-copy" env_factor=""
    else
        new="$work/bin/slow" env_factor="$algorithm=$factor"
    fi
    read -r first rest <<<"$thresholds"
    local start=$SECONDS status=0 load
    load=$(cut -d' ' -f1 /proc/loadavg)
    # shellcheck disable=SC2086
    TETBENCH_SCRATCH_SLOWDOWN=$env_factor "$work/bin/base" ab "$work/bin/base" "$new" \
        --pairs "$pairs" --threshold "$first" --out "$out" $matrix >"$out.log" 2>&1 || status=$?
    verdict "$out/compare/compare.json" "$algorithm" "$n" "$factor" "$first" "$status" \
        "$((SECONDS - start))" "$load"
    for t in $rest; do
        status=0
        "$work/bin/base" compare "$out/base" "$out/new" --paired --threshold "$t" \
            --fail-on regression --out "$out/compare-$t" >"$out-$t.log" 2>&1 || status=$?
        verdict "$out/compare-$t/compare.json" "$algorithm" "$n" "$factor" "$t" "$status" \
            "$((SECONDS - start))" "$load"
    done
}

for n in $(seq 1 "$trials"); do
    for factor in same $factors; do
        if [ -n "$deadline" ] && [ "$(date +%s)" -ge "$deadline" ]; then
            echo "ab-power: deadline reached" >&2
            break 2
        fi
        trial "$n" "$factor"
    done
done

python3 - "$csv" "$algorithm" <<'EOF'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
alg = sys.argv[2]
print(f"| threshold | NEW | trials | {alg} found slower | trials with a false call | exit 3 | seconds per trial |")
print("|---:|---|---:|---:|---:|---:|---:|")
for threshold in dict.fromkeys(r["threshold"] for r in rows):
    for factor in dict.fromkeys(r["factor"] for r in rows):
        rs = [r for r in rows if (r["threshold"], r["factor"]) == (threshold, factor)
              and r["found"] != "error"]
        if not rs:
            continue
        found = sum(int(r["found"]) > 0 for r in rs)
        false = sum(int(r["false_calls"]) > 0 for r in rs)
        exit3 = sum(r["exit"] == "3" for r in rs)
        secs = sorted(int(r["seconds"]) for r in rs)
        name = "same build" if factor == "same" else f"{alg} ×{factor}"
        found_cell = "—" if factor == "same" else f"{found} of {len(rs)}"
        print(f"| {threshold} | {name} | {len(rs)} | {found_cell} | {false} of {len(rs)} | {exit3} | {secs[len(secs) // 2]} |")
errors = sum(r["found"] == "error" for r in rows)
if errors:
    print(f"\n{errors} trial(s) ended without a comparison (see their .log)")
EOF
