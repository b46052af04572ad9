#!/usr/bin/env bash
# Adaptive against uniform refinement on examples/adaptive_block.yaml (a
# block pressed on half its top: singular strain along the pressed edge and
# the held base's edges). Only displacements are prescribed, so every
# answer's strain energy U_h bounds the exact one from above and the lower
# energy is the closer answer; the exact energy is extrapolated from the
# three uniform meshes (Aitken), which gives each answer's true relative
# error in the energy norm, sqrt(2 (U_h - U)) over sqrt(2 (U_h - U) + 2 U_h),
# beside the estimate the summary reports, and their ratio (the estimate's
# effectivity).
#
# Prints a table: mesh, elements, unknowns, estimated error, strain energy,
# true error, effectivity, wall time (the adaptive rows: all cycles up to
# that one).
#
# With `finite`, the same block at finite strain: neo-Hookean (mu = 1000
# Pa, K = 9667 Pa: the linear block's nu = 0.45), pressed 1 mm (10 %
# nominal), NONLINEAR_STATIC on plain TET4 (a conforming element whose
# energy bounds the exact one as in the linear case; TET4_ANP's nodal
# volumes would not). The estimate is then that of the second
# Piola-Kirchhoff stress measured with the initial compliance.
#
# Usage: scripts/bench_adapt.sh [cycles [linear|finite]]   (default 5 linear)
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${PBA_BUILD_DIR:-$root/build/release}
solve=$build/bin/pba-solve
cycles=${1:-5}
mode=${2:-linear}
[ -x "$solve" ] || { echo "bench_adapt: build pba-solve first ($solve)" >&2; exit 2; }

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
example=$root/examples/adaptive_block.yaml
if [ "$mode" = finite ]; then
  sed -e 's/  linear_elastic:/  neo_hookean:/' \
      -e 's/youngs_modulus_pa: 3000/shear_modulus_pa: 1000/' \
      -e 's/poissons_ratio: 0.45/bulk_modulus_pa: 9667/' \
      -e 's/z_mm: -0.2/z_mm: -1/' \
      -e 's/type: LINEAR_STATIC/type: NONLINEAR_STATIC/' "$example" >"$work/finite.yaml"
  example=$work/finite.yaml
elif [ "$mode" != linear ]; then
  echo "bench_adapt: mode is linear or finite, not $mode" >&2
  exit 2
fi

run() {  # name scene -> one JSON line of the figures
  local name=$1 scene=$2
  "$solve" "$scene" --out "$work/out" --progress none --force
  python3 - "$work/out/summary.json" "$name" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
print(json.dumps({"mesh": sys.argv[2], "elements": int(s["modelled"]["elements"]),
                  "dofs": int(s["modelled"]["dofs"]),
                  "estimate": s["error_estimate"]["relative_error"],
                  "energy": s["results"]["strain_energy_j"],
                  "wall": s["performance"]["wall_time_s"]}))
PY
}

: >"$work/rows"
for size in 2.5 1.25 0.625; do
  sed -e "s/element_size_mm: 2.5/element_size_mm: $size/" \
      -e '/^  adapt:/,/^    max_elements:/d' "$example" >"$work/uniform.yaml"
  run "uniform $size mm" "$work/uniform.yaml" >>"$work/rows"
done
for k in $(seq 1 "$cycles"); do
  sed -e "s/target_error_percent: 20/target_error_percent: 1/" \
      -e "s/max_elements: 100000/max_elements: 1000000\n    max_cycles: $k/" "$example" \
      >"$work/adaptive.yaml"
  run "adaptive, cycle $k" "$work/adaptive.yaml" >>"$work/rows"
done

echo "machine: $(nproc) cores; commit $(git -C "$root" rev-parse --short HEAD); $mode"
python3 - "$work/rows" <<'PY'
import json, math, sys
rows = [json.loads(line) for line in open(sys.argv[1])]
u1, u2, u3 = (r["energy"] for r in rows[:3])
exact = (u1 * u3 - u2 * u2) / (u1 + u3 - 2 * u2)
print(f"extrapolated exact strain energy {exact:.5g} J (Aitken, uniform 2.5, 1.25, 0.625 mm)")
print("| mesh | elements | unknowns | estimated error | strain energy [J] | true error | effectivity | wall time |")
print("|---|---|---|---|---|---|---|---|")
for r in rows:
    e2 = 2 * max(r["energy"] - exact, 0)
    true = math.sqrt(e2 / (e2 + 2 * r["energy"]))
    print(f"| {r['mesh']} | {r['elements']:,} | {r['dofs']:,} | {100 * r['estimate']:.3g} % | "
          f"{r['energy']:.5g} | {100 * true:.3g} % | {r['estimate'] / true:.2f} | "
          f"{r['wall']:.3g} s |")
PY
