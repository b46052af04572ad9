#!/usr/bin/env bash
# Speed against error, element by element, on the thick sphere and the
# uniaxial compression: runs
# element_bench (tests/bench/element_bench.cc), keeps its CSV and draws the
# true error against the wall time, one curve per element and problem, in
# docs/figures/speed_vs_error.png (the Pareto front a user chooses from).
# Usage: scripts/plot_speed_vs_error.sh [extra Google Benchmark flags]
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${PBA_BUILD_DIR:-$root/build/release}
export CCACHE_BASEDIR=$root

"$root/scripts/deps.sh"
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" -j "${PBA_JOBS:-2}" --target element_bench
csv="$build/element_bench.csv"
"$build/bin/element_bench" --benchmark_out="$csv" --benchmark_out_format=csv "$@" >/dev/null

# One data file per problem and element: wall time [s], true error [%].
data=$(mktemp -d)
trap 'rm -rf "$data"' EXIT
awk -F, -v dir="$data" '
  /^"BM_/ {
    gsub(/"/, "", $1)
    split($1, part, "/")
    problem = part[1]; sub(/^BM_/, "", problem)
    element = part[3]; sub(/^element:/, "", element)
    names[0] = "TET4"; names[1] = "TET4_ANP"; names[2] = "TET10"; names[3] = "HEX8"; names[4] = "TET10_MD"
    print $13, $14 >> (dir "/" problem "_" names[element] ".dat")
  }' "$csv"

plots=()
for f in "$data"/*.dat; do
  label=$(basename "$f" .dat)
  label=${label/LameSphere_/Lamé, }
  label=${label/InflatedSphere_/inflation, }
  label=${label/Uniaxial_/uniaxial, }
  # One colour per element, one line style per problem.
  case $label in
    *TET4_ANP) colour=1 ;; *TET4) colour=2 ;; *TET10_MD) colour=3 ;; *TET10) colour=4 ;; *) colour=5 ;;
  esac
  case $label in
    Lam*) style="dt 1 pt 7" ;; inflation*) style="dt 2 pt 5" ;; *) style="dt 3 pt 9" ;;
  esac
  plots+=("'$f' using 1:2 with linespoints lw 2 lc $colour $style title '$label'")
done
out="$root/docs/figures/speed_vs_error.png"
gnuplot <<GNUPLOT
set terminal pngcairo size 900,600 font "sans,11" noenhanced
set output "$out"
set logscale xy
set format x "%g"
set format y "%g"
set xlabel "wall time of the solve [s] (2 cores)"
set ylabel "true error [%]"
set title "Thick sphere and uniaxial compression: speed against error (element_bench)"
set key outside right
set grid
plot $(IFS=,; echo "${plots[*]}")
GNUPLOT
echo "wrote $out from $csv"
