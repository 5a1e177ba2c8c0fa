#!/usr/bin/env bash
# Measures `tetbench compare` on separate runs of one build (docs/regression.md, "Busy
# machine"): each consecutive pair of RUNS runs is compared as it is (the same build: any
# regression is a false call, any exit 1 the time-noise refusal) and again with NEW's work
# counters injected +2 % (`fragments` and `ray_steps` of every row multiplied by 1.02 and
# rounded up, written into a copy of NEW's results.json: what the exact gate must find).
#
# usage: scripts/work-gate-power.sh TETBENCH OUT [RUNS]   (prints one line per comparison)
set -euo pipefail
bin=$(realpath "$1")
out=$2
runs=${3:-11}
mkdir -p "$out"
matrix=(--algorithms gator-pt,havs,fragment-pt,raycast --datasets box:10k --resolution 64
        --viewpoints +x,+x+y+z,-x+y-z
        --frames 1 --warmup 1 --rounds 3 --no-reference --no-calibrate --no-report)
for i in $(seq 1 "$runs"); do
    [ -f "$out/run-$i/results.json" ] && continue
    "$bin" run "${matrix[@]}" --out "$out/run-$i" > "$out/run-$i.log" 2>&1
done
inject() { # DIR → DIR-inj: fragments and ray_steps ×1.02 in every row
    rm -rf "$2"; cp -r "$1" "$2"
    python3 - "$2/results.json" <<'PY'
import json, math, sys
p = sys.argv[1]
f = json.load(open(p))
for r in f["rows"]:
    c = r["counters"]
    if isinstance(c, dict):
        for k in ("fragments", "ray_steps"):
            if c.get(k):
                c[k] = float(math.ceil(c[k] * 1.02))
json.dump(f, open(p, "w"), indent=1)
PY
}
summary() { # compare.json, exit status → one line
    python3 - "$1" "$2" "$3" <<'PY'
import json, sys
c = json.load(open(sys.argv[1] + "/compare.json"))
regs = c["regressions"]
work = sorted({r["metric"] for r in regs if r["verdict"] in ("more", "less", "added", "removed")})
time = [r["group"] for r in regs if r["metric"] == "total_ms"]
print(f'{sys.argv[3]:<10} exit {sys.argv[2]}  run-wide x{c["run_factor"] or 0:.3f}  '
      f'spread x{c.get("group_spread") or 0:.3f}  too_noisy {c["too_noisy"]}  '
      f'work regressions {len([r for r in regs if r["verdict"] == "more"])} ({",".join(work)})  '
      f'time regressions {len(time)}')
PY
}
for i in $(seq 1 $((runs - 1))); do
    j=$((i + 1))
    set +e
    "$bin" compare --fail-on regression --out "$out/cmp-$i-same" "$out/run-$i" "$out/run-$j" > /dev/null 2> "$out/cmp-$i-same.err"
    s=$?
    summary "$out/cmp-$i-same" $s "same-$i"
    inject "$out/run-$j" "$out/run-$j-inj"
    "$bin" compare --fail-on regression --out "$out/cmp-$i-inj" "$out/run-$i" "$out/run-$j-inj" > /dev/null 2> "$out/cmp-$i-inj.err"
    s=$?
    summary "$out/cmp-$i-inj" $s "inj-$i"
    set -e
done
python3 - "$out" "$runs" <<'PY'
import json, sys
for i in range(1, int(sys.argv[2]) + 1):
    m = json.load(open(f"{sys.argv[1]}/run-{i}/results.json"))["machine"]
    print(f'run-{i}: load {m.get("load_average_start")} → {m.get("load_average_end")} on {m["cpu_cores"]} cores, {m["date_utc"]}')
PY
