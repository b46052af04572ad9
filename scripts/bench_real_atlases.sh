#!/usr/bin/env bash
# The real-atlas figures of docs/atlas.md: the atlases of Debian's
# mricron-data (installed by scripts/deps.sh) meshed one after the other,
# each in one pba-atlas command from the files it ships with, under
# /usr/bin/time -v. One Markdown row per build: structures, tetrahedra,
# wall time, peak memory, the mesh's volume against the voxels of the
# labels.nii.gz it was made from, how many structures miss the quality
# bounds (aspect-ratio p99 >= 5, smallest dihedral angle <= 5 degrees), the
# smallest dihedral angle and its structure, and what the build took out or
# moved (short edges collapsed with the largest surface move, slivers
# peeled off the outer surface, fragments dropped).
#
# Usage: scripts/bench_real_atlases.sh [case ...]
#   cases: aal6 jhu6 aicha6 aal3 aal2 (default: all, in that order)
#   PBA_BENCH_KEEP=dir keeps each build's output in dir/<case>
#   PBA_BENCH_STRUCTURES=dir writes dir/<case>.md, the quality and volume
#     of every structure (docs/real_atlases/ holds them)
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${PBA_BUILD_DIR:-$root/build/release}
atlas=$build/bin/pba-atlas
[ -x "$atlas" ] || { echo "bench_real_atlases: build pba-atlas first" >&2; exit 2; }
t=/usr/share/mricron/templates
[ -f "$t/aal.nii.gz" ] || { echo "bench_real_atlases: $t missing (scripts/deps.sh installs mricron-data)" >&2; exit 2; }
py=/usr/bin/python3

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cases=("$@")
[ ${#cases[@]} -gt 0 ] || cases=(aal6 jhu6 aicha6 aal3 aal2)

aal=(--labels "$t/aal.nii.gz" --colour-table "$t/aal.nii.txt" --fill "White matter" --closing-mm 7)
jhu=(--labels "$t/JHU-WhiteMatter-labels-1mm.nii.gz" --colour-table "$t/JHU-WhiteMatter-labels-1mm.nii.txt")
aicha=(--labels "$t/AICHAmc.nii.gz" --colour-table "$t/AICHAmc.nii.txt")
at() { echo --cell-mm "$1" --facet-mm "$1" --no-pictures; }

echo "| build | structures | tetrahedra | time | peak memory | mesh / voxel volume | AR p99 ≥ 5 | smallest dihedral ≤ 5° | smallest dihedral | short edges collapsed (largest surface move) | slivers peeled | fragments dropped |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
for c in "${cases[@]}"; do
  case $c in
    aal6) args=("${aal[@]}" $(at 6)) ;;
    jhu6) args=("${jhu[@]}" $(at 6)) ;;
    aicha6) args=("${aicha[@]}" $(at 6)) ;;
    aal3) args=("${aal[@]}" $(at 3)) ;;
    aal2) args=("${aal[@]}" $(at 2)) ;;
    *) echo "bench_real_atlases: unknown case $c" >&2; exit 2 ;;
  esac
  out=$work/$c
  if ! /usr/bin/time -v -o "$work/$c.time" "$atlas" build -o "$out" "${args[@]}" >"$work/$c.log" 2>&1; then
    echo "bench_real_atlases: $c failed:" >&2
    tail -5 "$work/$c.log" >&2
    exit 1
  fi
  "$py" - "$c" "$out" "$work/$c.log" "$work/$c.time" "${PBA_BENCH_STRUCTURES:-}" "$(printf '%q ' "${args[@]}")" <<'EOF'
import csv, gzip, re, struct, sys
import numpy as np

case, out, log, timing, structures_dir, command = sys.argv[1:]
rows = list(csv.DictReader(open(f"{out}/quality.csv")))
overall = next(r for r in rows if r["structure"] == "overall")
rows = [r for r in rows if r["structure"] != "overall"]
ar_miss = sum(float(r["AR p99"]) >= 5 for r in rows)
angle_miss = sum(float(r["min dihedral [deg]"]) <= 5 for r in rows)
worst = min(rows, key=lambda r: float(r["min dihedral [deg]"]))
mesh_cm3 = sum(float(r["volume [mm^3]"]) for r in rows) / 1e3

# The voxels of labels.nii.gz (NIfTI-1): those with a label, times the voxel volume.
raw = gzip.open(f"{out}/labels.nii.gz").read()
dims = struct.unpack("<8h", raw[40:56])
datatype = struct.unpack("<h", raw[70:72])[0]
pixdim = struct.unpack("<8f", raw[76:108])
offset = int(struct.unpack("<f", raw[108:112])[0])
dtype = {2: np.uint8, 4: np.int16, 512: np.uint16, 8: np.int32}[datatype]
count = int(np.prod(dims[1:4]))
labels = np.frombuffer(raw, dtype=dtype, count=count, offset=offset)
voxel_cm3 = np.count_nonzero(labels) * pixdim[1] * pixdim[2] * pixdim[3] / 1e3

text = open(log).read()
def note(pattern, fmt, default="0"):
    m = re.search(pattern, text)
    return fmt(m) if m else default
collapsed = note(r"note: (\d+) short edges? collapsed [^\n]*?(?:by at most ([0-9.]+) mm|only nodes inside)",
                 lambda m: f"{m[1]} ({m[2]} mm)" if m[2] else f"{m[1]} (inside only)")
peeled = note(r"note: (\d+) slivers? on the outer surface taken out \(([0-9.e+-]+) mm\^3",
              lambda m: f"{m[1]} ({float(m[2]):.3g} mm³)")
fragments = note(r"note: (\d+) fragments? of the mesh .*?, ([0-9.e+-]+) mm\^3",
                 lambda m: f"{m[1]} ({float(m[2]):.3g} mm³)")
t = open(timing).read()
wall = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (?:(\d+):)?(\d+):([0-9.]+)", t)
seconds = int(wall[1] or 0) * 3600 + int(wall[2]) * 60 + float(wall[3])
rss_mb = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", t)[1]) / 1024
tetrahedra = f"{int(overall['elements']):,}".replace(",", " ")
if structures_dir:
    # Each structure: its tetrahedra, its quality, and its mesh volume
    # against its own voxels in labels.nii.gz.
    voxel_mm3 = pixdim[1] * pixdim[2] * pixdim[3]
    counts = np.bincount(labels.astype(np.int64))
    with open(f"{structures_dir}/{case}.md", "w") as md:
        command = command.strip().replace("/usr/share/mricron/templates", "$T")
        md.write(f"# {case}: every structure\n\n"
                 f"`pba-atlas build -o {case}/ {command}`, with\n"
                 f"`T=/usr/share/mricron/templates` (the command of `scripts/bench_real_atlases.sh {case}`,\n"
                 f"whose `PBA_BENCH_STRUCTURES` writes this file), {len(rows)} structures,\n"
                 f"{tetrahedra} tetrahedra. The quality bounds: aspect-ratio p99 under 5,\n"
                 f"every dihedral angle over 5°; a structure missing one is in bold. The\n"
                 f"voxel volume is the structure's voxels in the build's `labels.nii.gz`.\n\n"
                 "| structure | label | tetrahedra | mesh volume [mm³] | voxel volume [mm³] | difference | "
                 "AR median | AR p99 | AR max | smallest dihedral |\n"
                 "|---|---|---|---|---|---|---|---|---|---|\n")
        for r in rows:
            label = int(r["label"])
            voxels = (counts[label] if label < len(counts) else 0) * voxel_mm3
            mesh = float(r["volume [mm^3]"])
            missed = float(r["AR p99"]) >= 5 or float(r["min dihedral [deg]"]) <= 5
            name = f"**{r['structure']}**" if missed else r["structure"]
            diff = f"{100 * (mesh / voxels - 1):+.1f} %" if voxels > 0 else "–"
            md.write(f"| {name} | {label} | {int(r['elements'])} | {mesh:.0f} | {voxels:.0f} | {diff} | "
                     f"{float(r['AR median']):.2f} | {float(r['AR p99']):.2f} | {float(r['AR max']):.2f} | "
                     f"{float(r['min dihedral [deg]']):.1f}° |\n")
print(f"| {case} | {len(rows)} | {tetrahedra} | {seconds:.0f} s | {rss_mb:.0f} MB | "
      f"{mesh_cm3:.1f} / {voxel_cm3:.1f} cm³ ({100 * (mesh_cm3 / voxel_cm3 - 1):+.1f} %) | "
      f"{ar_miss} | {angle_miss} | {float(worst['min dihedral [deg]']):.1f}° ({worst['structure']}) | "
      f"{collapsed} | {peeled} | {fragments} |")
EOF
  if [ -n "${PBA_BENCH_KEEP:-}" ]; then
    mkdir -p "$PBA_BENCH_KEEP"
    rm -rf "${PBA_BENCH_KEEP:?}/$c"
    mv "$out" "$PBA_BENCH_KEEP/$c"
  fi
done
