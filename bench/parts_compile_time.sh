#!/bin/sh
# Where a model file's compile goes (issue 38): the plugin unit of FILE's
# whole entry and of several parts (src/run/run_parts.h), compiled one after
# the other with the plugin's compiler and flags (build/generated/
# estlab_plugin_config.h), as CPU seconds and the compiler's peak MB. Run it
# on an idle machine.
#
#   bench/parts_compile_time.sh [FILE [MEASUREMENT]]
#       (default: examples/models/pendulum.model sin)
#
# Environment: ESTLAB (default build/estlab), BUILD (default build).
set -eu
file=$(realpath "${1:-examples/models/pendulum.model}")
meas=${2:-sin}
estlab=$(realpath "${ESTLAB:-build/estlab}")
config=${BUILD:-build}/generated/estlab_plugin_config.h
define() { sed -n "s/^#define $1 \"\(.*\)\"$/\1/p" "$config"; }
cxx=$(define ESTLAB_PLUGIN_CXX)
flags="$(define ESTLAB_PLUGIN_FLAGS) $(define ESTLAB_PLUGIN_SOURCE_INCLUDES)"
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
"$estlab" model source "$file" --out "$dir" > /dev/null
# The unit's head (the header, model_entry_impl.h, ESTLAB_MODEL_TYPE).
sed -n '1,/^#endif/p' "$dir/entry.cpp" > "$dir/head"
unit() {  # unit NAME MEASUREMENT FILTER ADAPT SMOOTH SIMULATE
  { cat "$dir/head"
    printf 'struct Parts {\n  static constexpr const char* kMeasurement = %s;\n' "$2"
    printf '  static constexpr int kFilter = %s;\n' "$3"
    printf '  static constexpr bool kAdapt = %s, kSmooth = %s, kSimulate = %s;\n};\n' "$4" "$5" "$6"
    echo 'ESTLAB_DEFINE_MODEL_PARTS_PLUGIN(ESTLAB_MODEL_TYPE, Parts)'; } > "$dir/$1.cpp"
}
unit whole nullptr -1 true true true
unit meas_every_filter "\"$meas\"" -1 true true false
unit meas_sigma "\"$meas\"" 2 true true false
unit meas_sigma_plain "\"$meas\"" 2 false false false
unit simulator nullptr -2 false false true
unit description nullptr -2 false false false
printf '%-18s %7s %8s  %s\n' unit cpu_s peak_MB parts
while read -r u what; do
  # shellcheck disable=SC2086  # flags are words
  (cd "$dir" && /usr/bin/time -f '%U %S %M' -o "$dir/time" sh -c "$cxx $flags $u.cpp -o $u.so")
  awk -v u="$u" -v w="$what" '{ printf "%-18s %7.1f %8.0f  %s\n", u, $1 + $2, $3 / 1024, w }' \
    "$dir/time"
done <<EOF
whole every measurement and filter class, adapter, smoother, simulator (entry.so)
meas_every_filter $meas, every filter class, adapter, smoother
meas_sigma $meas, the sigma-point class, adapter, smoother
meas_sigma_plain $meas, the sigma-point class (run-$meas-sigma.so)
simulator the simulator alone (run-all-none-sim.so)
description the description alone (run-all-none.so)
EOF
