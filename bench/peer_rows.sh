#!/bin/sh
# The peer comparison rows of issue 39 (done-when 1), in one run on the same
# data: estlab's microseconds per step through `estlab filter` (the
# summary's us_per_step: the filter loop alone) for
#   - the paper-002 pendulum UKF: 2 states, y = sin(theta), Euler,
#     dt 0.0125, alpha 1e-3, beta 2, kappa 0, sigma points redrawn after
#     the prediction; 400 000 steps;
#   - a 4-state constant-velocity UKF (FilterPy's example shape: dt 0.1,
#     positions measured, white-acceleration Q; examples/models/cv2d.model,
#     compiled on first use); 50 000 steps;
# and the bench's UKF/cv2d/n4m2/euler row. Best and median of RUNS runs.
#
#   bench/peer_rows.sh [BUILD_DIR] [RUNS]      (default: build 5)
#
# Targets on the 2-core machine: the pendulum UKF at most 0.16 us per step
# through the command, the cv2d row at most 0.23 us (docs/performance.md).
set -eu
build=${1:-build}
runs=${2:-5}
here=$(cd "$(dirname "$0")/.." && pwd)
estlab="$build/estlab"
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
"$estlab" simulate --model pendulum --x0 theta=0.5 --t-end 4999.9875 --dt 0.0125 \
  --integrator euler --measure sin --meas-noise-var 0.01 --process-noise-var 1e-6,1e-4 \
  --seed 1 --out "$dir/pendulum.csv" > /dev/null
"$estlab" simulate --model "$here/examples/models/cv2d.model" --x0 vx=1,vy=0.5 \
  --t-end 4999.9 --dt 0.1 --integrator discrete --measure positions --meas-noise-var 1,1 \
  --process-noise-var 0.001,0.001,0.01,0.01 \
  --seed 2 --out "$dir/cv2d.csv" > /dev/null 2>&1
per_step() {  # the runs' us_per_step, best and median
  for i in $(seq "$runs"); do
    "$estlab" filter "$@" --json | python3 -c 'import json,sys; print(json.load(sys.stdin)["us_per_step"])'
  done | sort -g | awk '{v[NR]=$1} END {printf "best %.3f  median %.3f us/step", v[1], v[int((NR+1)/2)]}'
}
echo "pendulum UKF, 400 000 steps, estlab filter: $(per_step --model pendulum \
  --data "$dir/pendulum.csv" --measure sin --filter ukf --integrator euler --alpha 1e-3 \
  --beta 2 --kappa 0 --x0 theta=0.5 --p0-diag 0.1,0.1 --q-diag 1e-6,1e-4 --r-diag 0.01)"
echo "cv2d UKF, 50 000 steps, estlab filter:      $(per_step \
  --model "$here/examples/models/cv2d.model" --data "$dir/cv2d.csv" --measure positions \
  --filter ukf --integrator discrete --x0 vx=1,vy=0.5 --p0-diag 10,10,1,1 \
  --q-white-accel 0.1 --r-diag 1,1)"
if [ -x "$build/bench/estlab_bench" ]; then
  "$build/bench/estlab_bench" --benchmark_filter='^UKF/cv2d/n4m2/euler$' \
    --benchmark_repetitions="$(( runs < 2 ? 2 : runs ))" --benchmark_report_aggregates_only=true \
    2>/dev/null |
    awk '/_median|_mean/ {print "bench row " $1 ": " $2 " " $3}'
else
  echo "bench row UKF/cv2d/n4m2/euler: build with -DESTLAB_BUILD_BENCH=ON (make bench)"
fi
