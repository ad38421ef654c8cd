#!/bin/sh
# What a new model costs before its first result (issue 38): for each model
# file, with a fresh model cache, the commands a user runs first, each as
# wall time, CPU time (estlab and the compiler) and the compiler's peak
# resident memory:
#   sim     `simulate` (compiles run-all-none-sim.so: the simulator alone),
#   filter  `filter --filter ukf` on that data (compiles run-<m>-sigma.so: one
#           measurement's runner with the sigma-point filters),
#   tune    `tune --filter ukf --max-iterations 2` (compiles tune.so, the Q/R
#           tuner; the iterations are capped so that the column is the
#           compile),
#   entry   `model build` in a fresh cache (entry.so: every filter, the
#           simulator; what a study and `list` load),
# then a cached load (best of 5 of `estlab list --model FILE`).
# The first measurement of the model file is used, with Q = 1e-4 I and
# R = 1e-2 I. Targets (issue 38): first filter <= 10 s, first tune <= 20 s,
# cached load <= 10 ms wall, on the 2-core development machine. Run it on an
# idle machine: a compile uses one core.
#
#   bench/compile_time.sh [--no-tune] [MODEL_FILE...]   (default: examples/models/*.model)
#
# Environment: ESTLAB (default build/estlab).
set -eu
tune=1
if [ "${1:-}" = "--no-tune" ]; then tune=0; shift; fi
estlab=$(realpath "${ESTLAB:-build/estlab}")
[ $# -gt 0 ] || set -- examples/models/*.model
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
timed() {  # timed CMD...: wall, user+sys CPU (children included), peak MB; any exit status
  /usr/bin/time -f '%e %U %S %M' -o "$dir/time" "$@" > "$dir/out" 2> "$dir/err" || true
  if grep -q "error" "$dir/err"; then echo "failed: $*" >&2; cat "$dir/err" >&2; fi
  awk '{ printf "%7.1f %7.1f %6.0f", $1, $2 + $3, $4 / 1024 }' "$dir/time"
}
dash() { printf '%7s %7s %6s' - - -; }
printf '%-30s %3s | %7s %7s %6s | %7s %7s %6s | %7s %7s %6s | %7s %7s %6s | %9s\n' model n \
  sim_s cpu_s MB filter_s cpu_s MB tune_s cpu_s MB entry_s cpu_s MB cached_ms
for file in "$@"; do
  file=$(realpath "$file")
  cache="$dir/cache"
  rm -rf "$cache" "$dir/whole" "$dir/d.csv"
  # n, the first measurement and its outputs, from the file (no compile).
  set -- $("$estlab" model show "$file" --json | python3 -c 'import json, sys
m = json.load(sys.stdin)
meas = m["measurements"][0]
print(len(m["states"]), meas["name"], len(meas["outputs"]))')
  n=$1 meas=$2 outputs=$3
  ones() { python3 -c 'import sys; print(",".join([sys.argv[1]] * int(sys.argv[2])))' "$1" "$2"; }
  noise="--q-diag $(ones 1e-4 "$n") --r-diag $(ones 1e-2 "$outputs")"
  line=$(printf '%-30s %3s | ' "$(basename "$file")" "$n")
  line="$line$(cd "$dir" && timed "$estlab" --model-cache "$cache" simulate --model "$file" \
    --t-end 2 --dt 0.01 --measure "$meas" --meas-noise-var "$(ones 1e-2 "$outputs")" --out d.csv) | "
  line="$line$(cd "$dir" && timed "$estlab" --model-cache "$cache" filter --model "$file" \
    --measure "$meas" --data d.csv --filter ukf $noise --out f.csv) | "
  if [ "$tune" = 1 ]; then
    line="$line$(cd "$dir" && timed "$estlab" --model-cache "$cache" tune --model "$file" \
      --measure "$meas" --data d.csv --filter ukf --init-q-diag "$(ones 1e-4 "$n")" \
      --init-r-diag "$(ones 1e-2 "$outputs")" --max-iterations 2) | "
  else
    line="$line$(dash) | "
  fi
  line="$line$(timed "$estlab" --model-cache "$dir/whole" model build "$file" --json) | "
  best=""
  for _ in 1 2 3 4 5; do
    ms=$(python3 -c 'import subprocess,sys,time
t=time.perf_counter(); subprocess.run(sys.argv[1:], check=True, stdout=subprocess.DEVNULL)
print("%.2f" % (1e3 * (time.perf_counter() - t)))' "$estlab" --model-cache "$dir/whole" list --model "$file")
    best=$(python3 -c 'import sys; a=sys.argv[1]; print(sys.argv[2] if not a else min(float(a), float(sys.argv[2])))' "$best" "$ms")
  done
  printf '%s%9s\n' "$line" "$best"
done
