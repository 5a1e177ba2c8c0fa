#!/usr/bin/env bash
# Runs one `tetbench run` matrix on a Slurm cluster: a job array of N shards (`run --shard i/N`,
# one output directory each), then a job that starts once every array task has ended (whether
# it succeeded or not: afterany) and merges the shards with `report --merge`. See
# docs/cluster.md.
#
#   scripts/slurm-run.sh --shards N --out DIR [options] -- [tetbench run options]
#
# Options:
#   --shards N        number of array tasks, one shard each
#   --out DIR         on a file system every node sees: DIR/shard-I/ (one per shard),
#                     DIR/logs/ (Slurm's output of every task), DIR/merged/ (the merged report),
#                     DIR/slurm/ (the two job scripts, for resubmitting a failed shard)
#   --gpu             one GPU per task (sbatch --gres=gpu:1)
#   --tetbench BIN    the binary (default: $CARGO_TARGET_DIR/release/tetbench, else
#                     the repository's target/release/tetbench); it too must be on a shared file system
#   --sbatch ARG      an extra sbatch option for both jobs, repeatable (--sbatch --partition=gpu)
#   --shared-ok       skip the shared-path test: you know DIR and BIN are visible on every node
#   --allow-missing   merge even when shards failed; the merged results list the missing units
#                     in their errors (default: the merge job refuses and names the shards)
#   --fail-shard I    for testing: shard I fails on purpose (exit 42) instead of running
#
# The shared-path test: when every node of the cluster is this host (a one-node cluster, such as
# CI's), every path is seen by every node and passes, /tmp included — unless Slurm gives each
# job a private /tmp (JobContainerType=job_container/tmpfs). On any other cluster DIR and BIN
# must not be under /tmp, /var/tmp, /dev/shm or $TMPDIR nor on tmpfs (node-local everywhere),
# and must be on a network or parallel file system (NFS, Lustre, GPFS, BeeGFS, CephFS, …).
# Anything else is refused unless --shared-ok says otherwise.
set -euo pipefail

die() {
    echo "slurm-run: $*" >&2
    exit 2
}

shards="" out="" gpu=0 bin="" shared_ok=0 allow_missing=0 fail_shard=""
sbatch_args=()
while [ $# -gt 0 ]; do
    case "$1" in
    --shards) shards="${2:-}" && shift 2 ;;
    --out) out="${2:-}" && shift 2 ;;
    --gpu) gpu=1 && shift ;;
    --tetbench) bin="${2:-}" && shift 2 ;;
    --sbatch) sbatch_args+=("${2:-}") && shift 2 ;;
    --shared-ok) shared_ok=1 && shift ;;
    --allow-missing) allow_missing=1 && shift ;;
    --fail-shard) fail_shard="${2:-}" && shift 2 ;;
    --) shift && break ;;
    -h | --help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//' && exit 0 ;;
    *) die "unknown option $1 (tetbench run's options go after --; see --help)" ;;
    esac
done
run_args=("$@")

[[ "$shards" =~ ^[1-9][0-9]*$ ]] || die "--shards N needs a positive whole number, got '${shards}'"
[ -n "$out" ] || die "--out DIR is required (a directory every node of the cluster sees)"
if [ -n "$fail_shard" ]; then
    [[ "$fail_shard" =~ ^[0-9]+$ ]] && [ "$fail_shard" -ge 1 ] && [ "$fail_shard" -le "$shards" ] ||
        die "--fail-shard $fail_shard: expected a shard between 1 and $shards"
fi
for a in "${run_args[@]}"; do
    case "$a" in
    --out | --out=* | --shard | --shard=*)
        die "do not pass $a to tetbench run: this script sets --shard i/N and --out DIR/shard-i" ;;
    esac
done
command -v sbatch >/dev/null 2>&1 ||
    die "sbatch not found: run this on a Slurm login node (or install Slurm's client, e.g. apt-get install slurm-client)"

if [ -z "$bin" ]; then
    # Where cargo built it: $CARGO_TARGET_DIR, else target/ at the repository root (not the
    # current directory, so the script works from anywhere).
    bin="${CARGO_TARGET_DIR:-$(cd "$(dirname "$0")/.." && pwd)/target}/release/tetbench"
    [ -x "$bin" ] || die "no tetbench binary at $bin: build it (cargo build --release -p harness --bin tetbench) or pass --tetbench BIN"
fi
[ -x "$bin" ] && [ -f "$bin" ] || die "--tetbench $bin: not an executable file"
bin="$(cd "$(dirname "$bin")" && pwd)/$(basename "$bin")"
mkdir -p "$out" || die "cannot create $out"
out="$(cd "$out" && pwd)"

# Whether every node of the cluster is this host (sinfo answers and names no other node).
only_this_host() {
    local me others
    me="$(hostname -s)"
    sinfo -h -N -o '%n' >/dev/null 2>&1 || return 1
    others="$(sinfo -h -N -o '%n %N' 2>/dev/null | tr ' ' '\n' | sort -u |
        grep -v -x -e '' -e "$me" -e "$(hostname)" -e localhost || true)"
    [ -z "$others" ]
}
# Whether Slurm mounts a private /tmp (and /dev/shm) for each job: job_container/tmpfs.
private_job_tmp() {
    scontrol show config 2>/dev/null | grep -q -E '^JobContainerType *= *job_container/tmpfs'
}

# Why PATH is not visible from every node, or nothing when it is (see the header).
not_shared_because() {
    local path="$1" tmp one_node=0
    only_this_host && one_node=1
    for tmp in /tmp /var/tmp /dev/shm ${TMPDIR:+"${TMPDIR%/}"}; do
        [ "$tmp" = / ] && continue
        case "$path/" in "$tmp"/*)
            if [ "$one_node" -eq 1 ]; then
                # The one node is this host: it sees this /tmp, unless each job gets its own.
                if private_job_tmp; then
                    echo "it is under $tmp, and this cluster gives each job a private $tmp (job_container/tmpfs)"
                fi
                return 0
            fi
            echo "it is under $tmp, which is local to each node"
            return
            ;;
        esac
    done
    # A one-node cluster whose node is this host sees every path of this host.
    [ "$one_node" -eq 1 ] && return 0
    local fstype
    fstype="$(findmnt -n -o FSTYPE -T "$path" 2>/dev/null || stat -f -c %T "$path" 2>/dev/null || echo unknown)"
    case "$fstype" in
    tmpfs | ramfs) echo "it is on $fstype, which is local to each node" ;;
    nfs* | lustre | gpfs | beegfs | ceph | fuse.ceph* | cifs | smb* | *gluster* | panfs | wekafs | \
        fuse.sshfs | fuse.juicefs | orangefs | pvfs2 | afs | 9p | virtiofs | autofs) ;;
    *)
        if sinfo -h -N -o '%n' >/dev/null 2>&1; then
            echo "it is on a local file system ($fstype) and the cluster has other nodes than $(hostname -s)"
        else
            echo "it is on a local file system ($fstype) and sinfo could not list the cluster's nodes"
        fi
        ;;
    esac
}
if [ "$shared_ok" -eq 0 ]; then
    for p in "$out" "$bin"; do
        why="$(not_shared_because "$p")"
        [ -z "$why" ] ||
            die "$p is not on a shared path: $why. Use a directory on the cluster's shared file system, or pass --shared-ok if every node does see it"
    done
fi

mkdir -p "$out/logs" "$out/slurm"
q() { # shell-quoted words, joined by spaces
    local IFS=' ' w=()
    local a
    for a in "$@"; do w+=("$(printf '%q' "$a")"); done
    echo "${w[*]}"
}
sbatch_lines() {
    local a
    for a in "${sbatch_args[@]}"; do printf '#SBATCH %s\n' "$a"; done
}

# One array task: runs shard SLURM_ARRAY_TASK_ID/N into its own directory and records the exit
# status there, so the merge job can tell a failure from a task that never finished.
{
    echo '#!/usr/bin/env bash'
    echo '#SBATCH --job-name=tetbench-shard'
    echo "#SBATCH --output=$(q "$out/logs/shard-%a.out")"
    echo '#SBATCH --ntasks=1'
    [ "$gpu" -eq 1 ] && echo '#SBATCH --gres=gpu:1'
    sbatch_lines
    echo "# Written by scripts/slurm-run.sh; rerun one shard with: sbatch --array=I $(q "$out/slurm/shard.sh")"
    echo 'set -u'
    echo "i=\"\${SLURM_ARRAY_TASK_ID:?run this script as a Slurm array task}\""
    echo "dir=$(q "$out")/shard-\$i"
    echo 'rm -rf "$dir" && mkdir -p "$dir" || exit 1'
    echo "echo \"tetbench shard \$i/$shards: job \${SLURM_ARRAY_JOB_ID:-?}_\$i on \$(hostname)\""
    if [ -n "$fail_shard" ]; then
        echo "if [ \"\$i\" = $fail_shard ]; then"
        echo "    echo \"shard \$i/$shards fails on purpose (slurm-run.sh --fail-shard)\" >&2"
        echo '    echo 42 >"$dir/exit-status"; exit 42'
        echo 'fi'
    fi
    echo "$(q "$bin" run "${run_args[@]}") --shard \"\$i/$shards\" --out \"\$dir\""
    echo 'status=$?'
    echo 'echo "$status" >"$dir/exit-status"'
    echo 'exit "$status"'
} >"$out/slurm/shard.sh"

# The merge: names every shard that failed (its exit status, Slurm's state, its log's tail);
# merges nothing when a shard wrote no results, unless --allow-missing; `report --merge` then
# checks completeness again from the shards' results.json (each records its i/N and whether
# it finished). A shard that failed with its results written (failed rows) is merged, and the
# job still fails, as `tetbench run` does with failed rows.
{
    echo '#!/usr/bin/env bash'
    echo '#SBATCH --job-name=tetbench-merge'
    echo "#SBATCH --output=$(q "$out/logs/merge.out")"
    echo '#SBATCH --ntasks=1'
    sbatch_lines
    echo '# Written by scripts/slurm-run.sh. Argument: the array job id (for Slurm'"'"'s view of a failed task).'
    echo 'set -u'
    echo "out=$(q "$out") n=$shards allow_missing=$allow_missing array_job=\"\${1:-}\""
    cat <<'EOF'
slurm_state() { # the task's state and exit code as Slurm saw it, when it still knows
    [ -n "$array_job" ] || return 0
    local s
    s="$(sacct -n -X -P -j "${array_job}_$1" -o State,ExitCode 2>/dev/null | head -n 1)"
    [ -n "$s" ] && echo "Slurm: ${s/|/, exit code }" && return 0
    s="$(scontrol -o show job "${array_job}_$1" 2>/dev/null | grep -o -E '(JobState|ExitCode)=[^ ]+' | tr '\n' ' ')"
    [ -n "$s" ] && echo "Slurm: $s"
    return 0
}
failed=() missing=() arrived=()
for i in $(seq 1 "$n"); do
    d="$out/shard-$i"
    status="$(cat "$d/exit-status" 2>/dev/null || true)"
    if [ -f "$d/results.json" ]; then
        arrived+=("$d")
        [ "$status" = 0 ] && continue
    else
        missing+=("$i")
    fi
    failed+=("$i")
    if [ -n "$status" ] && [ -f "$d/results.json" ]; then
        why="exited with status $status (its results.json is there: failed rows are recorded in it)"
    elif [ -n "$status" ]; then
        why="exited with status $status before writing results"
    elif [ -f "$d/results.json" ]; then
        why="was killed while running (no exit status; its results.json is partial)"
    else
        why="never ran or was killed before writing anything (cancelled, time limit, node failure)"
    fi
    echo "tetbench: shard $i/$n failed: it $why. $(slurm_state "$i")" >&2
    if [ -f "$out/logs/shard-$i.out" ]; then
        echo "  last lines of $out/logs/shard-$i.out:" >&2
        tail -n 15 "$out/logs/shard-$i.out" | sed 's/^/    /' >&2
    else
        echo "  no log at $out/logs/shard-$i.out" >&2
    fi
done
rerun() {
    local list
    list="$(IFS=,; echo "$*")"
    echo "Rerun shard(s) $list, then merge again:" >&2
    echo "  job=\$(sbatch --parsable --array=$list $out/slurm/shard.sh)" >&2
    echo "  sbatch --dependency=afterany:\$job $out/slurm/merge.sh \$job" >&2
}
if [ "${#missing[@]}" -gt 0 ] && [ "$allow_missing" -eq 0 ]; then
    echo "tetbench: not merging: shard(s) $(IFS=,; echo "${missing[*]}") of $n wrote no results." >&2
    rerun "${missing[@]}"
    echo "Or merge what arrived, listing the missing units: slurm-run.sh --allow-missing, or tetbench report --merge ... --allow-missing" >&2
    exit 1
fi
[ "${#arrived[@]}" -gt 0 ] || { echo "tetbench: no shard wrote results; nothing to merge" >&2; exit 1; }
extra=()
[ "$allow_missing" -eq 1 ] && extra+=(--allow-missing)
# report --merge refuses a shard whose results.json is unfinished (killed or crashed mid-run),
# and a missing one, naming them; with --allow-missing it lists their units instead.
EOF
    echo "$(q "$bin") report --merge \"\${arrived[@]}\" --out \"\$out/merged\" \"\${extra[@]}\" || exit"
    cat <<'EOF'
# Merged, but like an unsharded run with failed rows, the job fails when a shard did.
if [ "${#failed[@]}" -gt 0 ]; then
    echo "tetbench: merged into $out/merged, but shard(s) $(IFS=,; echo "${failed[*]}") of $n failed (above)" >&2
    rerun "${failed[@]}"
    exit 1
fi
EOF
} >"$out/slurm/merge.sh"
chmod +x "$out/slurm/shard.sh" "$out/slurm/merge.sh"

array_job="$(sbatch --parsable --array="1-$shards" --chdir="$PWD" "$out/slurm/shard.sh")" ||
    die "sbatch refused the array job (see above)"
array_job="${array_job%%;*}"
merge_job="$(sbatch --parsable --dependency="afterany:$array_job" --chdir="$PWD" \
    "$out/slurm/merge.sh" "$array_job")" || {
    scancel "$array_job" 2>/dev/null || true
    die "sbatch refused the merge job (the array job $array_job was cancelled)"
}
merge_job="${merge_job%%;*}"
printf 'ARRAY_JOB=%s\nMERGE_JOB=%s\nMERGED=%q\n' "$array_job" "$merge_job" "$out/merged" \
    >"$out/slurm/jobs.env"
echo "array job $array_job: $shards shards into $out/shard-{1..$shards} (logs in $out/logs)"
echo "merge job $merge_job (after all of them): merged report in $out/merged"
