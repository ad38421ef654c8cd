#!/bin/sh
# How a study scales with --jobs (issue 37). For each job count: the wall
# time the study reports (`--json` wall_s), the speed-up over the first
# count, and whether runs.csv, steps.csv, summary.csv and tuned.csv are the
# same bytes as the first count's. Then, from the first count's task times
# (`task_work_s`, `critical_path_s`: the task pool's work and its longest
# chain, a tuning then a run waiting for it), the speed-up the scheduler
# allows at 16 jobs: work / max(critical path, work / 16).
#
#   bench/study_scaling.sh CONFIG RUNS JOBS...   (e.g. studies/tuning_hand_vs_auto.ini 100 1 2)
#
# Environment: ESTLAB (default build/estlab).
set -eu
[ $# -ge 3 ] || { echo "usage: bench/study_scaling.sh CONFIG RUNS JOBS..." >&2; exit 2; }
config=$1
runs=$2
shift 2
estlab=${ESTLAB:-build/estlab}
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
key() {  # key FILE NAME: a number of the --json summary
  python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))[sys.argv[2]])' "$1" "$2"
}
first=""
printf '%-6s %10s %9s %s\n' jobs wall_s speedup same_bytes
for jobs in "$@"; do
  out="$dir/j$jobs"
  "$estlab" study "$config" --runs "$runs" --jobs "$jobs" --out "$out" --quiet --json > "$dir/j$jobs.json"
  wall=$(key "$dir/j$jobs.json" wall_s)
  if [ -z "$first" ]; then
    first=$out
    base=$wall
    work=$(key "$dir/j$jobs.json" task_work_s)
    path=$(key "$dir/j$jobs.json" critical_path_s)
    same="-"
  else
    same=yes
    for f in runs.csv steps.csv summary.csv tuned.csv; do
      if [ -e "$first/$f" ] || [ -e "$out/$f" ]; then
        cmp -s "$first/$f" "$out/$f" || same="no ($f)"
      fi
    done
  fi
  python3 -c 'import sys; j,w,b,s=sys.argv[1:]; print("%-6s %10.2f %9.2f %s" % (j, float(w), float(b)/float(w), s))' \
    "$jobs" "$wall" "$base" "$same"
done
python3 -c 'import sys; w,p=map(float,sys.argv[1:]); print("task work %.2f s, critical path %.2f s: at most %.1fx at 16 jobs" % (w, p, w / max(p, w / 16)))' \
  "$work" "$path"
