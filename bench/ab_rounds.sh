#!/usr/bin/env bash
# Two bench binaries (e.g. the parent commit's and this tree's) run in
# alternating rounds over the rows of issue 16, each round three interleaved
# repetitions; prints the medians over rounds and the ratio new / base.
#
#   bench/ab_rounds.sh BASE_BENCH NEW_BENCH OUT_DIR [ROUNDS]   # default 2 rounds
set -euo pipefail
base=$1 new=$2 out=$3 rounds=${4:-2}
mkdir -p "$out"
rows='^(UKF/cv2d/n4m2/euler|UKF/double-pendulum/n4m2/rk4|EKF/double-pendulum/n4m2/rk4'
rows+='|EKF/double-pendulum/n4m2/cvodes-rtol1e-8'
rows+='|Floor/double-pendulum/(rk4-with-jacobian/x1|rk4/x9|cvodes-with-sensitivities/x1)|Floor/cv2d/euler/x9'
rows+='|PF/(pendulum/n2m1|double-pendulum/n4m2)/rk4/systematic-every-step/1000)$'
for r in $(seq 1 "$rounds"); do
  for which in base new; do
    bin=$base
    [ "$which" = new ] && bin=$new
    uptime >"$out/load_${which}_$r.txt"
    "$bin" --benchmark_color=false --benchmark_filter="$rows" --benchmark_min_time=0.3 \
      --benchmark_repetitions=3 --benchmark_enable_random_interleaving=true \
      --benchmark_report_aggregates_only=true --benchmark_out_format=json \
      --benchmark_out="$out/steps_${which}_$r.json" >"$out/steps_${which}_$r.txt" 2>&1
  done
done
python3 - "$out" <<'PY'
import collections, glob, json, statistics, sys
rows = collections.defaultdict(lambda: collections.defaultdict(list))
for path in glob.glob(sys.argv[1] + "/steps_*_*.json"):
    which = path.rsplit("steps_", 1)[1].split("_")[0]
    for b in json.load(open(path))["benchmarks"]:
        if b.get("aggregate_name") == "median":
            rows[b["run_name"]][which].append((b["cpu_time"], b["time_unit"]))
print("| row | base | new | new/base |\n|---|---:|---:|---:|")
for name in sorted(rows):
    base = statistics.median(t for t, _ in rows[name]["base"])
    new = statistics.median(t for t, _ in rows[name]["new"])
    unit = rows[name]["new"][0][1]
    print(f"| {name} | {base:.4g} {unit} | {new:.4g} {unit} | {new / base:.3f} |")
PY
