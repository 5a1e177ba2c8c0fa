#!/usr/bin/env bash
# CI: a real one-node Slurm cluster runs scripts/slurm-run.sh end to end (issue 28).
#  1. Installs slurm-wlm and munge when absent; starts a private munged, slurmctld and slurmd
#     (state, spool, sockets and logs in one temporary directory; ports chosen free).
#  2. A 3-shard array of a small matrix plus its merge job: the merged rows must equal one
#     plain run of the same matrix in every key and image hash, in the same order.
#  3. The same array with --gpu (one stand-in GPU) and shard 2 made to fail: the merge job
#     must fail and name shard 2/3, and `report --merge` of the two shards that arrived must
#     refuse (naming 2/3) unless --allow-missing, which lists the missing units.
# Every wait is bounded; on failure it prints squeue, the jobs' state and the logs' tails. The
# daemons it started are stopped by their pids on exit.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/common.sh
started=$(date +%s)
repo="$PWD"

log() { echo "ci-slurm: $*" >&2; }

need=()
for c in sbatch slurmctld slurmd munged; do command -v "$c" >/dev/null 2>&1 || need+=("$c"); done
if [ "${#need[@]}" -gt 0 ]; then
    log "installing slurm-wlm and munge (missing: ${need[*]})"
    apt_install slurm-wlm munge
fi
command -v python3 >/dev/null 2>&1 || apt_install python3
ensure_prerequisites

# The debug binary the test suite has already built (cheap to bring up to date here).
cargo build -q -p harness --bin tetbench
bin="${CARGO_TARGET_DIR:-$repo/target}/debug/tetbench"
case "$bin" in /*) ;; *) bin="$repo/$bin" ;; esac

# The daemons run as root; started directly (not through a shell function) so that $! is the
# daemon's own pid.
root=()
[ "$(id -u)" -eq 0 ] || root=(sudo)
tmp="$(mktemp -d "${TMPDIR:-/tmp}/tetbench-slurm.XXXXXX")"
chmod 700 "$tmp"
out="$repo/out/ci-slurm"
rm -rf "$out"
mkdir -p "$out" "$tmp"/{munge,state,spool}
pids=() jobs_seen=()
cleanup() {
    local status=$?
    local p
    # Jobs still queued or running (after a failure) go first: their processes outlive slurmd.
    if [ "$status" -ne 0 ] && [ "${#jobs_seen[@]}" -gt 0 ]; then
        scancel "${jobs_seen[@]}" 2>/dev/null || true
        sleep 2
    fi
    # slurmd and slurmctld first, munged (which they authenticate through) last.
    for ((k = ${#pids[@]} - 1; k >= 0; k--)); do "${root[@]}" kill "${pids[k]}" 2>/dev/null || true; done
    for p in "${pids[@]}"; do
        for _ in $(seq 1 40); do kill -0 "$p" 2>/dev/null || break; sleep 0.25; done
        "${root[@]}" kill -9 "$p" 2>/dev/null || true
    done
    "${root[@]}" rm -rf "$tmp"
    log "finished in $(($(date +%s) - started)) s (status $status)"
}
trap cleanup EXIT

diagnose() {
    log "FAILED: $*"
    squeue --all -l 2>&1 | sed 's/^/  squeue: /' >&2 || true
    for j in "${jobs_seen[@]}"; do
        scontrol -o show job "$j" 2>&1 | grep -o -E '(JobId|ArrayTaskId|JobState|ExitCode|Reason)=[^ ]+' |
            tr '\n' ' ' | sed 's/^/  job: /' >&2 || true
        echo >&2
        sacct -X -j "$j" -o JobID,State,ExitCode 2>/dev/null | sed 's/^/  sacct: /' >&2 || true
    done
    for f in "$tmp"/slurmctld.log "$tmp"/slurmd.log "$tmp"/munged.log "$out"/*/logs/*.out; do
        [ -f "$f" ] && { echo "  --- tail of $f" >&2; tail -n 20 "$f" | sed 's/^/  /' >&2; }
    done
    exit 1
}

# munged on a private socket (a system munged, if the package started one, is left alone).
key="$tmp/munge/munge.key"
dd if=/dev/urandom of="$key" bs=1024 count=1 status=none
chmod 400 "$key"
sock="$tmp/munge/munge.socket"
"${root[@]}" munged --foreground --force --key-file="$key" --socket="$sock" \
    --pid-file="$tmp/munge/munged.pid" --seed-file="$tmp/munge/seed" \
    --log-file="$tmp/munged.log" >"$tmp/munged.out" 2>&1 &
pids+=($!)

free_port() { python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'; }
node="$(hostname -s)"
export SLURM_CONF="$tmp/slurm.conf"
cat >"$SLURM_CONF" <<EOF
# One node, no cgroups (CI runs in a container), no accounting database.
ClusterName=tetbench-ci
SlurmctldHost=$node(127.0.0.1)
SlurmUser=root
SlurmdUser=root
SlurmctldPort=$(free_port)
SlurmdPort=$(free_port)
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$sock
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/slurmctld.log
SlurmdLogFile=$tmp/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SwitchType=switch/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
SlurmdParameters=config_overrides
MinJobAge=600
# One stand-in GPU (gres.conf below), so that slurm-run.sh --gpu's --gres=gpu:1 is scheduled
# for real.
GresTypes=gpu
NodeName=$node NodeAddr=127.0.0.1 CPUs=2 Gres=gpu:1 State=UNKNOWN
PartitionName=ci Nodes=$node Default=YES MaxTime=INFINITE State=UP
EOF
# The stand-in GPU's device is /dev/null: slurmd counts a GPU only with a device file, and
# nothing here opens it (the tasks render on lavapipe).
printf 'AutoDetect=off\nNodeName=%s Name=gpu File=/dev/null Count=1\n' "$node" >"$tmp/gres.conf"
for _ in $(seq 1 40); do [ -S "$sock" ] && break; sleep 0.25; done
[ -S "$sock" ] || { cat "$tmp/munged.out" >&2; diagnose "munged did not start"; }
"${root[@]}" env SLURM_CONF="$SLURM_CONF" slurmctld -D -i -f "$SLURM_CONF" >"$tmp/slurmctld.out" 2>&1 &
pids+=($!)
"${root[@]}" env SLURM_CONF="$SLURM_CONF" slurmd -D -N "$node" -f "$SLURM_CONF" >"$tmp/slurmd.out" 2>&1 &
pids+=($!)
state=""
for _ in $(seq 1 60); do
    state="$(sinfo -h -n "$node" -o %T 2>/dev/null || true)"
    [ "$state" = idle ] && break
    sleep 1
done
[ "$state" = idle ] || {
    cat "$tmp"/slurm*.out >&2
    diagnose "node $node not idle after 60 s (state: '${state}')"
}
log "one-node Slurm up on $node ($(($(date +%s) - started)) s)"

# The matrix: two small meshes, the deterministic cell-projection algorithms, three views.
matrix=(--algorithms gator-pt,fragment-pt --settings 'sort=radix|bucket' --datasets box:2k,shell:2k
    --viewpoints +x,-x-y+z,+y --resolution 64 --frames 1 --warmup 0 --no-reference
    --no-calibrate --no-report --cache-dir "$out/cache")

wait_job() { # JOB SECONDS: waits for it to leave the queue, prints its final state
    local j="$1" limit="$2" s
    for _ in $(seq 1 "$limit"); do
        s="$(scontrol -o show job "$j" 2>/dev/null | grep -o -E 'JobState=[A-Z_]+' | cut -d= -f2)"
        case "$s" in COMPLETED | FAILED | CANCELLED | TIMEOUT | NODE_FAIL | OUT_OF_MEMORY | BOOT_FAIL | DEADLINE)
            echo "$s"
            return 0
            ;;
        esac
        sleep 1
    done
    diagnose "job $j still ${s:-unknown} after $limit s"
}

# 2. Three shards and their merge, against one plain run (run here while Slurm works).
scripts/slurm-run.sh --shards 3 --out "$out/array" --tetbench "$bin" -- "${matrix[@]}" >&2 ||
    diagnose "slurm-run.sh refused"
. "$out/array/slurm/jobs.env"
jobs_seen+=("$ARRAY_JOB" "$MERGE_JOB")
"$bin" run "${matrix[@]}" --out "$out/single" >"$out/single.log" 2>&1 ||
    { tail -n 20 "$out/single.log" >&2; diagnose "the plain run failed"; }
s="$(wait_job "$MERGE_JOB" 300)"
[ "$s" = COMPLETED ] || diagnose "merge job $MERGE_JOB ended $s"
python3 - "$out/single/results.json" "$MERGED/results.json" <<'EOF' || diagnose "merged rows differ from one run"
import json, sys
def rows(path):
    doc = json.load(open(path))
    keys = ("algorithm", "settings", "dataset", "viewpoint", "width", "height", "tets",
            "image_hash", "error")
    return doc, [tuple(r.get(k) for k in keys) for r in doc["rows"]]
single, a = rows(sys.argv[1])
merged, b = rows(sys.argv[2])
assert a, "the plain run has no rows"
assert all(r[7] for r in a), "a row without an image hash"
assert a == b, "rows differ:\n" + "\n".join(
    f"  one run: {x}\n  merged:  {y}" for x, y in zip(a + [None] * len(b), b + [None] * len(a)) if x != y)
parts = sorted(m["shard"] for m in merged["run"]["merged_from"])
assert parts == ["1/3", "2/3", "3/3"], parts
print(f"ci-slurm: merged rows equal one run: {len(a)} rows, {len(set(r[7] for r in a))} distinct images, from shards {parts}", file=sys.stderr)
EOF

# 3. Shard 2 fails: the merge job fails and names it; report --merge refuses the rest.
# With --gpu: each task asks for the node's one (stand-in) GPU, so the tasks run one by one.
scripts/slurm-run.sh --shards 3 --out "$out/fail" --tetbench "$bin" --gpu --fail-shard 2 -- "${matrix[@]}" >&2 ||
    diagnose "slurm-run.sh refused"
. "$out/fail/slurm/jobs.env"
jobs_seen+=("$ARRAY_JOB" "$MERGE_JOB")
s="$(wait_job "$MERGE_JOB" 300)"
[ "$s" = FAILED ] || diagnose "merge job $MERGE_JOB ended $s, expected FAILED"
grep -q 'shard 2/3 failed: it exited with status 42' "$out/fail/logs/merge.out" ||
    diagnose "the merge job's log does not name shard 2/3"
[ ! -e "$out/fail/merged/results.json" ] || diagnose "the failed merge wrote merged results"
scontrol -o show job "${ARRAY_JOB}_1" | grep -q -E 'gres[:/]gpu[:=]1' ||
    diagnose "shard 1 was not given a GPU (--gpu)"
log "merge job failed as it should: $(grep 'shard 2/3' "$out/fail/logs/merge.out" | head -n 1)"
if "$bin" report --merge "$out/fail/shard-1" "$out/fail/shard-3" --out "$out/fail/partial" 2>"$out/fail/partial.err"; then
    diagnose "report --merge of shards 1 and 3 of 3 succeeded"
fi
grep -q '2/3' "$out/fail/partial.err" || { cat "$out/fail/partial.err" >&2; diagnose "report --merge did not name shard 2/3"; }
"$bin" report --merge "$out/fail/shard-1" "$out/fail/shard-3" --out "$out/fail/partial" --allow-missing \
    >/dev/null 2>"$out/fail/partial.err" || { cat "$out/fail/partial.err" >&2; diagnose "report --merge --allow-missing failed"; }
python3 - "$out/fail/partial/results.json" <<'EOF' || diagnose "--allow-missing did not list the missing shard"
import json, sys
errors = json.load(open(sys.argv[1]))["errors"]
assert any("2/3" in e for e in errors), errors
EOF
log "report --merge refused shards 1 and 3 of 3, and --allow-missing listed shard 2's units"
