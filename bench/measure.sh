#!/usr/bin/env bash
# The measurement behind docs/performance.md: the per-step rows with 5
# repetitions (medians), the tuner and study rows with 3, each preceded by
# the machine load (uptime, running compilers). Build first with `make bench`.
#
#   bench/measure.sh [BUILD_DIR]      # default build; writes bench/results/
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
bench=$build/bench/estlab_bench
out=bench/results
mkdir -p "$out"
load() { echo "load: $(uptime | sed 's/.*load average/load average/'), compilers running: $(pgrep -c cc1plus || true)"; }
{
  load
  "$bench" --benchmark_color=false --benchmark_filter='^(KF|EKF|UKF|CKF|GHKF3|PF|Floor)/' \
    --benchmark_min_time=0.5 --benchmark_repetitions=5 --benchmark_report_aggregates_only=true \
    --benchmark_out="$out/steps.json" --benchmark_out_format=json
  load
  "$bench" --benchmark_color=false --benchmark_filter='^(Tuner|Study)/' \
    --benchmark_repetitions=3 --benchmark_report_aggregates_only=true \
    --benchmark_out="$out/slow.json" --benchmark_out_format=json
  load
} 2>&1 | tee "$out/measure.txt"
echo "tables: $out/steps.md $out/slow.md"
