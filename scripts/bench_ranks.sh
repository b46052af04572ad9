#!/usr/bin/env bash
# Strong scaling over MPI ranks: the scaling cube of docs/performance.md
# (a neo-Hookean 10 mm cube, bottom fixed, top pressed 10 % in two Newton
# increments) solved by pba-solve as one process and by `mpirun -np N`,
# each run alone. Prints one table row per run: the unknowns, Newton
# iterations, the conjugate-gradient iterations per solve (range; "-" for a
# direct solver), assembly, linear-solve and residual time per Newton
# iteration (the residuals: the line search's evaluations), wall time and
# the peak memory of the largest process.
#
# Usage: scripts/bench_ranks.sh [ranks...]           (default: 1 2)
#   PBA_BENCH_CASES: "element:cells:K/mu:solver ..."  (default below)
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${PBA_BUILD_DIR:-$root/build/release}
solve=$build/bin/pba-solve
ranks_list=("$@")
[ ${#ranks_list[@]} -gt 0 ] || ranks_list=(1 2)
cases=${PBA_BENCH_CASES:-"TET10:16:10:AMG TET4_ANP:32:10:AMG TET10:10:10:MUMPS"}
[ -x "$solve" ] || { echo "bench_ranks: build pba-solve first ($solve)" >&2; exit 2; }

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# Open MPI refuses root unless told; ranks may outnumber the cores.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_rmaps_base_oversubscribe=1

echo "machine: $(nproc) cores, $(awk '/MemTotal/ {printf "%.0f GB", $2 / 1048576}' /proc/meminfo); commit $(git -C "$root" rev-parse --short HEAD)"
echo "| element | cells per edge | K/μ | unknowns | solver | ranks | threads per rank | Newton iterations | CG iterations | assembly per iteration | linear solve per iteration | residuals per iteration | wall time | peak memory (largest rank) |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
for case in $cases; do
  IFS=: read -r element cells k_mu solver <<<"$case"
  scene=$work/cube.yaml
  size=$(awk -v c="$cells" 'BEGIN { printf "%.10g", 10 / c }')
  cat >"$scene" <<EOF
name: bench-ranks
geometry: {box: {size_mm: [10, 10, 10]}}
mesh: {element: $element, element_size_mm: $size}
material: {neo_hookean: {shear_modulus_pa: 1000, bulk_modulus_pa: $((1000 * k_mu))}}
boundary_conditions:
  - {set: bottom, fixed: {}}
  - {set: top, displacement: {z_mm: -1}}
analysis:
  type: NONLINEAR_STATIC
  linear_solver: $solver
  nonlinear: {increments: 2}
outputs: {reaction_sets: [top]}
EOF
  for ranks in "${ranks_list[@]}"; do
    out=$work/out-$ranks
    rm -rf "$out"
    launcher=()
    [ "$ranks" -gt 1 ] && launcher=(mpirun -np "$ranks" --bind-to none)
    /usr/bin/time -f "%M" -o "$work/rss" "${launcher[@]}" "$solve" "$scene" --out "$out" \
      --progress none
    python3 - "$out/summary.json" "$(cat "$work/rss")" "$element" "$cells" "$k_mu" "$solver" "$ranks" <<'PY'
import json, re, sys
summary = json.load(open(sys.argv[1]))
rss_kb, element, cells, k_mu, solver, ranks = sys.argv[2:]
m = summary["modelled"]
c = summary["results"]["convergence"]
p = summary["performance"]
its = max(1, c["newton_iterations"])
cg = re.search(r"(\d+-\d+) iterations", m["linear_solver"])
cg = cg.group(1).replace("-", "–") if cg else "–"
if "redone by MUMPS" in m["linear_solver"]:
    cg += " (fallbacks)"
print(f"| {element} | {cells} | {k_mu} | {int(m['dofs']):,} | {solver} | {ranks} | {p['threads']} "
      f"| {c['newton_iterations']} | {cg} | {c['assembly_s'] / its:.2f} s "
      f"| {c['linear_solve_s'] / its:.2f} s | {c['residual_s'] / its:.2f} s "
      f"| {p['wall_time_s']:.1f} s "
      f"| {int(rss_kb) / 1024:,.0f} MB |")
PY
  done
done
