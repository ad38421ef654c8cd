#!/usr/bin/env bash
# A user model's cost against the built-in it re-writes: the rows of
# double-pendulum-file (examples/models/double_pendulum.model, built into the
# bench by estlab_add_model) and of the built-in double-pendulum, interleaved
# at random, REPS repetitions each; prints median CPU times and file/built-in
# ratios (docs/performance.md). Build first with `make bench`.
#
#   bench/user_model_ratio.sh [BUILD_DIR] [REPS]     # default build 10
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
reps=${2:-10}
out=bench/results
mkdir -p "$out"
echo "load: $(uptime | sed 's/.*load average/load average/'), compilers running: $(pgrep -c cc1plus || true)"
"$build/bench/estlab_bench" --benchmark_color=false \
  --benchmark_filter='^(EKF|UKF)/double-pendulum(-file)?/n4m2/rk4$|^RunFilter/double-pendulum' \
  --benchmark_min_time=0.3 --benchmark_repetitions="$reps" \
  --benchmark_enable_random_interleaving=true --benchmark_report_aggregates_only=true \
  --benchmark_out="$out/user_model.json" --benchmark_out_format=json > /dev/null
python3 - "$out/user_model.json" <<'PY'
import json, sys
rows = {b["run_name"]: b["cpu_time"] for b in json.load(open(sys.argv[1]))["benchmarks"]
        if b.get("aggregate_name") == "median"}
print(f"{'row (median CPU time)':58s} {'built-in':>10s} {'file':>10s} {'file/built-in':>14s}")
for name, t in sorted(rows.items()):
    if "double-pendulum-file" in name:
        base = rows.get(name.replace("double-pendulum-file", "double-pendulum"))
        if base:
            print(f"{name:58s} {base:10.4g} {t:10.4g} {t / base:14.3f}")
PY
