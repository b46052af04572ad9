#!/usr/bin/env bash
# Mesh-convergence studies of the flagship quasi-static scenes
# (docs/scenes.md, "Mesh convergence"): starts pba-server on a free loopback
# port with a fresh data directory (one job at a time, so each mesh's wall
# time is its own), runs `pba study convergence` on each scene's key
# results over four or five meshes around the example's own, and writes
# each table to OUT/<scene>.convergence.csv beside the printed table
# (OUT/<scene>.txt).
#
# The finest meshes take minutes each (3 to 23 on a 2-core machine), a
# whole run about an hour. Name scenes to run some of them.
#
# Usage: scripts/study_scenes.sh OUT [indentation|surgical_load|brain_shift|tumour_growth ...]
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${PBA_BUILD_DIR:-$root/build/release}
bin=$build/bin
[ $# -ge 1 ] || { echo "usage: $0 OUT [scene ...]" >&2; exit 2; }
out=$(mkdir -p "$1" && cd "$1" && pwd)
shift
scenes=("$@")
[ ${#scenes[@]} -gt 0 ] || scenes=(tumour_growth indentation surgical_load brain_shift)
for tool in pba pba-server pba-solve; do
  [ -x "$bin/$tool" ] || { echo "study_scenes: build $tool first ($bin/$tool)" >&2; exit 2; }
done

data=$(mktemp -d "${TMPDIR:-/tmp}/pba-study.XXXXXX")
# shellcheck source=scripts/local_server.sh
source "$root/scripts/local_server.sh"
stop_server() {
  stop_local_server || true
  rm -rf "$data"
}
trap stop_server EXIT
# One job at a time, so that each mesh's wall time is its own.
start_local_server "$bin" "$data" --max-running 1

# Each scene's key results (paths into its summary, docs/results.md) and
# element sizes, the example's own among them (a region of interest's size
# is scaled with the element size).
study() {
  local scene=$1 sizes=$2
  shift 2
  local quantities=()
  for q in "$@"; do quantities+=(-q "$q"); done
  echo "== $scene: element sizes $sizes mm"
  "$bin/pba" --server "$address" --timeout 120 study convergence "$root/examples/$scene.yaml" \
    "${quantities[@]}" --sizes "$sizes" --parallel 1 -o "$out/$scene.convergence.csv" |
    tee "$out/$scene.txt"
}

for scene in "${scenes[@]}"; do
  case $scene in
    tumour_growth)
      # The putamen's and the ventricles' largest displacement, the energy.
      study tumour_growth 20,14.14,10,7.071 'results.structure_displacements[2].max_mm' \
        'results.structure_displacements[1].max_mm' results.strain_energy_j ;;
    indentation)
      # The punch's force (the base's reaction: the same to 1e-13 N).
      study indentation 24,16.97,12,8.485,6 'results.reactions[0].force_n[2]' \
        results.max_displacement_mm ;;
    surgical_load)
      # The load patch's force, the dorsomedial thalamus's mean sinking.
      study surgical_load 17,12,8.5,6 'results.reactions[1].force_n[2]' \
        'results.structure_displacements[33].mean_mm[2]' results.max_displacement_mm ;;
    brain_shift)
      study brain_shift 16.97,12,8.485,6 'results.structure_displacements[33].mean_mm[2]' \
        results.max_displacement_mm ;;
    *) echo "study_scenes: no study for '$scene'" >&2; exit 2 ;;
  esac
done
