#!/usr/bin/env bash
# Makes synthetic nightly runs from a committed baseline, to measure `tetbench history` and
# `tetbench publish` at a year's scale (docs/regression.md, "History and site at scale"):
#
#   scripts/synthetic-history.sh BASELINE_DIR OUT_DIR [N] [--seed S] [--step-at K]
#                                [--step-algorithm ALG] [--step-factor F]
#
# Writes OUT_DIR/run-0000 … run-(N-1) (N = 1000 by default), each a copy of BASELINE_DIR's
# results.json (and calibration.json) with a commit and a start date of its own (one day
# apart) and every row's times (median, range, per-frame samples; fps and tets/s inversely)
# scaled by one factor drawn from U(0.9, 1.1) with a fixed seed (1 by default). From run K on
# (300 by default) the rows of ALG (havs by default) are F times slower (1.3 by default): one
# series family with a step, every other series without one. Same arguments, same files.
set -euo pipefail
usage="usage: scripts/synthetic-history.sh BASELINE_DIR OUT_DIR [N] [--seed S] [--step-at K] [--step-algorithm ALG] [--step-factor F]"
base="${1:?$usage}"
out="${2:?$usage}"
shift 2
n=1000
if [ $# -gt 0 ] && [[ "$1" != --* ]]; then
    n="$1"
    shift
fi
seed=1 step_at=300 step_alg=havs step_factor=1.3
while [ $# -gt 0 ]; do
    case "$1" in
        --seed) seed="$2"; shift 2 ;;
        --step-at) step_at="$2"; shift 2 ;;
        --step-algorithm) step_alg="$2"; shift 2 ;;
        --step-factor) step_factor="$2"; shift 2 ;;
        *) echo "$usage" >&2; exit 2 ;;
    esac
done
[ -f "$base/results.json" ] || { echo "synthetic-history: $base/results.json does not exist" >&2; exit 1; }
command -v python3 >/dev/null || { echo "synthetic-history: needs python3" >&2; exit 1; }
mkdir -p "$out"
python3 - "$base" "$out" "$n" "$seed" "$step_at" "$step_alg" "$step_factor" <<'EOF'
import datetime, hashlib, json, os, random, shutil, sys

base, out, n, seed, step_at, step_alg, step_factor = sys.argv[1:]
n, seed, step_at, step_factor = int(n), int(seed), int(step_at), float(step_factor)
with open(os.path.join(base, "results.json")) as f:
    doc = json.load(f)
rows = doc["rows"]
times = ["total_ms", "cpu_ms", "gpu_ms", "total_ms_min", "total_ms_max", "cpu_ms_min",
         "cpu_ms_max", "gpu_ms_min", "gpu_ms_max", "normalized_time"]
rates = ["fps", "tets_per_sec", "limit_fraction"]
rng = random.Random(seed)
start = datetime.datetime(2025, 1, 1, 2, 0, 0)
calibration = os.path.join(base, "calibration.json")
for k in range(n):
    run = json.loads(json.dumps(doc))
    m = run["machine"]
    m["git_commit"] = hashlib.sha1(f"synthetic nightly {seed} {k}".encode()).hexdigest()
    m["git_dirty"] = False
    m["date_utc"] = (start + datetime.timedelta(days=k)).strftime("%Y-%m-%dT%H:%M:%SZ")
    run["finished_utc"] = (start + datetime.timedelta(days=k, minutes=20)).strftime("%Y-%m-%dT%H:%M:%SZ")
    for row in run["rows"]:
        f = rng.uniform(0.9, 1.1)
        if row["algorithm"] == step_alg and k >= step_at:
            f *= step_factor
        for key in times:
            if isinstance(row.get(key), (int, float)):
                row[key] *= f
        for key in rates:
            if isinstance(row.get(key), (int, float)) and row[key]:
                row[key] /= f
        for key, values in (row.get("samples") or {}).items():
            if key.endswith("_ms") and isinstance(values, list):
                row["samples"][key] = [v * f for v in values]
    d = os.path.join(out, f"run-{k:04d}")
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, "results.json"), "w") as f:
        json.dump(run, f, indent=2, ensure_ascii=False)
    if os.path.isfile(calibration):
        shutil.copy(calibration, d)
print(f"wrote {n} runs to {out} (seed {seed}; {step_alg} ×{step_factor} from run {step_at})")
EOF
