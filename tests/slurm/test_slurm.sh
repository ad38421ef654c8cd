#!/usr/bin/env bash
# `make test-slurm` (issue 17): a study through a real Slurm, on a one-node
# cluster on this machine (local_cluster.sh), checked against a local run.
#   1. studies' tiny slurm_test.ini locally (--jobs 2), and through
#      `estlab study --slurm 3`: the merge job's OUT is byte-identical to the
#      local run (runs.csv, steps.csv, summary.csv, time_metrics.csv);
#   2. a shard cancelled with scancel, the merge job cancelled with it
#      (--kill-on-invalid-dep), the same command submitted again: only that
#      shard runs again (the others' files untouched) and OUT is identical.
# Run as root (the Makefile uses sudo when needed). Usage: test_slurm.sh ESTLAB
set -euo pipefail
estlab=$(readlink -f "${1:?path of the estlab binary}")
here=$(cd "$(dirname "$0")" && pwd)
work=$(mktemp -d /tmp/estlab-slurm-test.XXXXXX)
chmod 755 "$work"
cluster="$work/cluster"
cleanup() { "$here/local_cluster.sh" stop "$cluster" || true; rm -rf "$work"; }
trap cleanup EXIT
eval "$("$here/local_cluster.sh" start "$cluster")"
export SLURM_CONF
cd "$work"
cp "$here/slurm_test.ini" study.ini

fail() { echo "test-slurm: FAIL: $*" >&2; exit 1; }
# Waits until none of the job ids is in the queue (at most $2 seconds).
wait_jobs() {
  local ids=$1 limit=$2
  for _ in $(seq "$limit"); do
    [ -z "$(squeue -h -j "$ids" 2>/dev/null)" ] && return 0
    sleep 1
  done
  squeue >&2; fail "jobs $ids still queued after $limit s"
}
same() {  # same DIR1 DIR2: the files that do not depend on sharding
  for f in runs.csv steps.csv summary.csv time_metrics.csv; do
    cmp -s "$1/$f" "$2/$f" || fail "$2/$f differs from $1/$f"
  done
}
job_ids() { sed -n 's/.*"array_job": "\([0-9]*\)".*"merge_job": "\([0-9]*\)".*/\1 \2/p'; }

start=$(date +%s)
"$estlab" study study.ini --out local --jobs 2 --quiet >/dev/null

# 1. Through Slurm: 3 array tasks and the merge, into a folder whose name
#    holds a space, quotes, '$', a backquote and a non-ASCII letter (issue 40:
#    the scripts quote every path; sbatch gets each as one word).
odd="via slurm 'q' \"dq\" \$HOME \`id\` é"
read -r array merge < <("$estlab" study study.ini --out "$odd" --slurm 3 --jobs 1 --json | job_ids)
[ -n "$merge" ] || fail "no job ids from --slurm"
echo "test-slurm: array job $array, merge job $merge"
wait_jobs "$array,$merge" 300
[ -f "$odd/summary.csv" ] || { cat "$odd.slurm"/logs/* >&2 || true; fail "the merge job wrote no $odd/summary.csv"; }
same local "$odd"
"$estlab" study --status "$odd" | tee status.txt
grep -qF "$odd: complete" status.txt || fail "--status does not say complete"
grep -q "3 of 3 shards complete" status.txt || fail "--status does not count 3 complete shards"
echo "test-slurm: merged result byte-identical to the local run (out: $odd)"

# 2. Shard 2 cancelled (it waits for a hold, so it never finishes), the merge
#    with it; resubmission runs shard 2 only.
read -r array merge < <("$estlab" study study.ini --out killed --slurm 3 --jobs 1 \
  --slurm-opts "--hold" --json | job_ids)
scontrol release "${array}_1" "${array}_3" "$merge"
for _ in $(seq 120); do
  [ -f killed.slurm/shard-1/summary.csv ] && [ -f killed.slurm/shard-3/summary.csv ] && break
  sleep 1
done
scancel "${array}_2"
wait_jobs "$array,$merge" 120
[ ! -e killed/summary.csv ] || fail "the merge ran although shard 2 was cancelled"
"$estlab" study --status killed | tee status.txt
grep -q "2 of 3 shards complete" status.txt || fail "--status does not count 2 complete shards"
before=$(cat killed.slurm/shard-1/study.state killed.slurm/shard-3/study.state | md5sum)
out=$("$estlab" study study.ini --out killed --slurm 3 --jobs 1 --json)
echo "$out" | grep -q '"pending_shards": \[2\]' || fail "resubmission did not pick shard 2 only: $out"
read -r array merge < <(echo "$out" | job_ids)
wait_jobs "$array,$merge" 300
same local killed
after=$(cat killed.slurm/shard-1/study.state killed.slurm/shard-3/study.state | md5sum)
[ "$before" = "$after" ] || fail "shards 1 and 3 were run again"
# Submitting once more has nothing left to do.
"$estlab" study study.ini --out killed --slurm 3 | grep -q "nothing to submit" ||
  fail "a merged study was submitted again"
echo "test-slurm: a cancelled shard resubmitted alone; result identical ($(( $(date +%s) - start )) s)"
