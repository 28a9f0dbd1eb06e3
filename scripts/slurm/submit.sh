#!/usr/bin/env bash
# submit.sh — run a raycost sweep as a Slurm job array plus a dependent merge job.
#
#   scripts/slurm/submit.sh [--wait] [--timeout SECONDS] [--photons] [--missing|--check] SPEC SHARDS OUT
#
# Submits scripts/slurm/sweep.sbatch as array 0-(SHARDS-1) (task K runs `raycost run SPEC
# --shard K/SHARDS --out OUT`, or with --photons `--photon-shard K/SHARDS`: one run's photons
# split instead of its sweep points), then scripts/slurm/merge.sbatch with --dependency=afterok:ARRAY
# (`raycost merge OUT/NAME`). Prints `ARRAY_JOB=<id>` and `MERGE_JOB=<id>` on stdout.
# With --wait it polls squeue until both jobs have left the queue (printing the queue whenever it
# changes), then prints one line per array task and for the merge, and exits 1 unless every task
# and the merge COMPLETED with exit code 0:0 and the merge started after the last task ended.
#
# An incomplete set (a task hit its time limit, a node failed): `--check` submits nothing and
# lists the shards whose file is missing (OUT/NAME/NAME.shard-K-of-SHARDS.csv, with --photons
# OUT/NAME/NAME.photon-shard-K-of-SHARDS.json) on a line `MISSING=K1,K2,...`, exit 0 when none is
# missing and 1 otherwise (no Slurm needed); `--missing` submits an array of just those indices
# (`--array=K1,K2,...`) and the merge after them (the merge alone when none is missing).
#
# Environment: RAYCOST (raycost binary; default `raycost` on PATH, resolved to an absolute path),
# NAME (experiment.name; default read from the spec's [experiment] table), RAYCOST_ARGS (extra
# words for `raycost run`, e.g. --resume). Slurm's own SBATCH_PARTITION, SBATCH_ACCOUNT,
# SBATCH_TIMELIMIT, ... apply to both jobs; SLURM_CONF selects the cluster (see cluster.sh env).
# Job logs go to OUT/slurm-logs/.
set -euo pipefail

HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
usage() { echo "usage: $0 [--wait] [--timeout SECONDS] [--photons] [--missing|--check] SPEC SHARDS OUT" >&2; exit 2; }
log() { printf 'submit.sh: %s\n' "$*" >&2; }
die() { log "error: $*"; exit 1; }

wait=0
timeout=3600
split=points
only=all
while [[ $# -gt 0 ]]; do
    case $1 in
    --wait) wait=1; shift ;;
    --photons) split=photons; shift ;;
    --missing) [[ $only == all ]] || usage; only=missing; shift ;;
    --check) [[ $only == all ]] || usage; only=check; shift ;;
    --timeout) [[ $# -ge 2 && $2 =~ ^[0-9]+$ ]] || usage; timeout=$2; shift 2 ;;
    --) shift; break ;;
    -*) usage ;;
    *) break ;;
    esac
done
[[ $# -eq 3 ]] || usage
spec=$1 shards=$2 out=$3
[[ -f $spec ]] || { log "error: spec $spec: no such file"; exit 2; }
[[ $shards =~ ^[1-9][0-9]*$ ]] || { log "error: SHARDS must be a positive integer, got '$shards'"; exit 2; }

# Jobs may run in another directory or on another node: pass absolute paths only.
spec=$(realpath "$spec")
[[ $only == check ]] || mkdir -p "$out"
out=$(realpath -m "$out")
raycost=${RAYCOST:-raycost}
if [[ $raycost == */* ]]; then
    raycost=$(realpath "$raycost")
else
    raycost=$(command -v "$raycost") || die "raycost not found on PATH (set RAYCOST=/path/to/raycost)"
fi
[[ -x $raycost ]] || die "RAYCOST=$raycost is not executable"

# experiment.name, from the [experiment] table of the spec (the merge job needs OUT/NAME).
name=${NAME:-$(awk '
    /^[[:space:]]*\[/ { section = $0; gsub(/[[:space:]]/, "", section); next }
    section == "[experiment]" && /^[[:space:]]*name[[:space:]]*=/ {
        sub(/^[^=]*=[[:space:]]*/, ""); sub(/[[:space:]]*(#.*)?$/, "")
        gsub(/^["\047]|["\047]$/, ""); print; exit
    }' "$spec")}
[[ -n $name ]] || die "no experiment.name in $spec (or set NAME=...)"

# --- which shards: all, or those whose file is missing ------------------------------------------
shard_file() { # K -> the file array task K leaves when it finished
    if [[ $split == photons ]]; then
        echo "$out/$name/$name.photon-shard-$1-of-$shards.json"
    else
        echo "$out/$name/$name.shard-$1-of-$shards.csv"
    fi
}
tasks=()
for ((k = 0; k < shards; k++)); do
    [[ $only != all && -s $(shard_file "$k") ]] || tasks+=("$k")
done
missing=$(IFS=,; echo "${tasks[*]}")
if [[ $only == check ]]; then
    if [[ ${#tasks[@]} -eq 0 ]]; then
        echo "MISSING="
        log "all $shards ${split%s} shards of $name are in $out/$name: merge them with raycost merge $out/$name"
        exit 0
    fi
    echo "MISSING=$missing"
    log "${#tasks[@]} of $shards ${split%s} shards of $name missing (no $(shard_file K) for K = $missing): resubmit just those with $0 --missing$([[ $split == photons ]] && echo ' --photons') $spec $shards $out"
    exit 1
fi

logs="$out/slurm-logs"
mkdir -p "$logs"
export SPEC=$spec SHARDS=$shards OUT=$out RAYCOST=$raycost NAME=$name SPLIT=$split
export RAYCOST_ARGS=${RAYCOST_ARGS:-}

array_job=
dependency=()
if [[ ${#tasks[@]} -gt 0 ]]; then
    array_job=$(sbatch --parsable --export=ALL --chdir="$out" --array="$missing" \
        --job-name="raycost-$name" --output="$logs/$name-sweep-%A_%a.out" "$HERE/sweep.sbatch")
    array_job=${array_job%%;*} # --parsable prints "id[;cluster]"
    [[ $array_job =~ ^[0-9]+$ ]] || die "could not parse the array job id from sbatch: '$array_job'"
    dependency=(--dependency="afterok:$array_job" --kill-on-invalid-dep=yes)
else
    log "no $split shard of $name is missing: submitting the merge alone"
fi
merge_job=$(sbatch --parsable --export=ALL --chdir="$out" "${dependency[@]}" \
    --job-name="raycost-$name-merge" \
    --output="$logs/$name-merge-%j.out" "$HERE/merge.sbatch")
merge_job=${merge_job%%;*}
[[ $merge_job =~ ^[0-9]+$ ]] || die "could not parse the merge job id from sbatch: '$merge_job'"
echo "ARRAY_JOB=$array_job"
echo "MERGE_JOB=$merge_job"
log "sweep $name: array tasks ${missing:-none} of $shards (job ${array_job:-none}), merge job $merge_job after them; logs in $logs"
[[ $wait -eq 1 ]] || exit 0

# --- wait ----------------------------------------------------------------------------------
jobs=$merge_job
[[ -z $array_job ]] || jobs=$array_job,$merge_job
want=${#tasks[@]} # array tasks submitted
fmt='%.18i %.9P %.24j %.8T %.10M %.6D %R'
deadline=$((SECONDS + timeout))
last=
while :; do
    if ! q=$(squeue -h -j "$jobs" -o "$fmt" 2>&1); then
        # squeue errors with "Invalid job id" once all the listed jobs have been purged.
        if [[ $q == *"Invalid job id"* ]]; then q=; else log "squeue: $q"; fi
    fi
    if [[ $q != "$last" && -n $q ]]; then
        printf '%s squeue:\n%s\n' "$(date -u +%T)" "$q"
        last=$q
    fi
    [[ -z $q ]] && break
    [[ $SECONDS -lt $deadline ]] || die "jobs $jobs still queued after ${timeout}s (left running)"
    sleep 2
done

# --- verdict ---------------------------------------------------------------------------------
# scontrol knows finished jobs for MinJobAge seconds (cluster.sh sets 600; Slurm's default is
# 300); after that only accounting (sacct, which needs slurmdbd) has them.
job_lines() { # jobid -> one line per job: JobId ArrayJobId ArrayTaskId JobName JobState ExitCode StartTime EndTime
    scontrol show job -o "$1" 2>/dev/null |
        grep -oE '^JobId=[0-9]+|ArrayJobId=[0-9]+|ArrayTaskId=[0-9]+|JobName=[^ ]+|JobState=[A-Z_]+|ExitCode=[0-9:]+|StartTime=[^ ]+|EndTime=[^ ]+' |
        awk '/^JobId=/ && NR > 1 { print "" } { printf "%s ", $0 } END { print "" }' | sed 's/ $//; /^$/d'
}
fields=JobID,JobName%24,State,ExitCode,Start,End
task_lines=
[[ -z $array_job ]] || task_lines=$(job_lines "$array_job" | sort -t= -k4,4n)
merge_line=$(job_lines "$merge_job")
if [[ -n $task_lines || -n $merge_line ]]; then
    echo "scontrol show job (array $array_job, merge $merge_job):"
    printf '%s\n' "$task_lines" "$merge_line" | sed '/^$/d; s/^/  /'
    # The same jobs in the job-completion log (jobcomp/filetxt): sacct -c lists them by their own
    # job ids, not as ARRAY_TASK. Informational; a cluster with slurmdbd answers sacct -X below.
    ids=$(printf '%s\n' "$task_lines" "$merge_line" | grep -oE '^JobId=[0-9]+' | cut -d= -f2 | paste -sd, -)
    if acct=$(sacct -X -j "$jobs" -o "$fields" 2>/dev/null) ||
        acct=$(sacct -c -j "$ids" -o "$fields" 2>/dev/null); then
        echo "sacct:"
        printf '%s\n' "$acct" | sed 's/^/  /'
    fi
    ntasks=$(grep -c . <<<"$task_lines" || true)
    nok=$(grep -c 'JobState=COMPLETED ExitCode=0:0' <<<"$task_lines" || true)
    [[ $ntasks -eq $want ]] || die "expected $want array tasks, scontrol shows $ntasks"
    [[ $nok -eq $want ]] || die "$((want - nok)) of $want array tasks did not complete with exit 0 (logs: $logs)"
    [[ $merge_line == *"JobState=COMPLETED ExitCode=0:0"* ]] ||
        die "merge job $merge_job did not complete: ${merge_line:-unknown} (log: $logs)"
    last_end=$(grep -oE 'EndTime=[^ ]+' <<<"$task_lines" | cut -d= -f2 | sort | tail -n1)
    merge_start=$(grep -oE 'StartTime=[^ ]+' <<<"$merge_line" | cut -d= -f2)
    [[ ! $merge_start < $last_end ]] || die "merge started ($merge_start) before the last array task ended ($last_end)"
    echo "all $want array tasks COMPLETED 0:0, last ended ${last_end:-(none)}; merge started $merge_start, COMPLETED 0:0"
else
    acct=$(sacct -X -n -P -j "$jobs" -o "$fields" 2>/dev/null) ||
        die "jobs $array_job/$merge_job are gone from scontrol and sacct has no accounting; check $logs"
    echo "sacct (array $array_job, merge $merge_job):"
    printf '%s\n' "$acct" | sed 's/^/  /'
    ntasks=$(grep -cE "^${array_job}_[0-9]+\|" <<<"$acct" || true)
    nok=$(grep -E "^${array_job}_[0-9]+\|" <<<"$acct" | grep -c '|COMPLETED|0:0|' || true)
    [[ $ntasks -eq $want && $nok -eq $want ]] ||
        die "$((want - nok)) of $want array tasks did not complete with exit 0 (logs: $logs)"
    grep -qE "^${merge_job}\|.*\|COMPLETED\|0:0\|" <<<"$acct" || die "merge job $merge_job did not complete"
    echo "all $want array tasks and the merge COMPLETED 0:0"
fi
