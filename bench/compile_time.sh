#!/bin/sh
# What a new model costs before its first result (issue 38): for each model
# file, with a fresh model cache, the first `filter` (compiles entry.so:
# metadata, transitions, simulator, every filter) and the first `tune`
# (compiles tune.so, the Q/R tuner), each as wall time, CPU time (estlab
# and the compiler) and the compiler's peak resident memory; then a cached
# load (best of 5 of `estlab list --model FILE`, which loads entry.so).
# Targets (issue 38): first filter <= 10 s, first tune <= 20 s, cached load
# <= 10 ms wall, on the 2-core development machine. Run it on an idle
# machine: the compiles use one core each.
#
#   bench/compile_time.sh [--no-tune] [MODEL_FILE...]   (default: examples/models/*.model)
#
# Environment: ESTLAB (default build/estlab).
set -eu
tune=1
if [ "${1:-}" = "--no-tune" ]; then tune=0; shift; fi
estlab=${ESTLAB:-build/estlab}
[ $# -gt 0 ] || set -- examples/models/*.model
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
timed() {  # timed OUT CMD...: wall, user+sys CPU (children included), peak MB
  /usr/bin/time -f '%e %U %S %M' -o "$dir/time" "$@" > "$OUT_FILE" 2> "$dir/err" || {
    echo "failed: $*" >&2; cat "$dir/err" >&2; return 1; }
  awk '{ printf "%8.1f %8.1f %7.0f", $1, $2 + $3, $4 / 1024 }' "$dir/time"
}
printf '%-34s %6s | %8s %8s %7s | %8s %8s %7s | %9s\n' model states \
  filter_s cpu_s peak_MB tune_s cpu_s peak_MB cached_ms
for file in "$@"; do
  cache="$dir/cache"
  rm -rf "$cache"
  states=$("$estlab" model check "$file" | sed -n 's/.*: \([0-9]*\) states.*/\1/p')
  line=$(printf '%-34s %6s | ' "$(basename "$file")" "$states")
  OUT_FILE="$dir/out"
  line="$line$(timed "$estlab" --model-cache "$cache" model build "$file" --json) | "
  if [ "$tune" = 1 ]; then
    line="$line$(timed "$estlab" --model-cache "$cache" model build "$file" --tuner --json) | "
  else
    line="$line$(printf '%8s %8s %7s' - - -) | "
  fi
  best=""
  for _ in 1 2 3 4 5; do
    ms=$(python3 -c 'import subprocess,sys,time
t=time.perf_counter(); subprocess.run(sys.argv[1:], check=True, stdout=subprocess.DEVNULL)
print("%.2f" % (1e3 * (time.perf_counter() - t)))' "$estlab" --model-cache "$cache" list --model "$file")
    best=$(python3 -c 'import sys; a=sys.argv[1]; print(sys.argv[2] if not a else min(float(a), float(sys.argv[2])))' "$best" "$ms")
  done
  printf '%s%9s\n' "$line" "$best"
done
