#include "service/overlap_check.h"

#include <spdlog/spdlog.h>

#include <cstdio>
#include <vector>

#include "atlas/structure_overlap.h"

namespace pba {
namespace {

StructureFormat ToStructureFormat(GeometryFormat format) {
  StructureFormat out = StructureFormat::kContours;
  ParseStructureFormat(GeometryFormatName(format), &out);
  return out;
}

}  // namespace

Status CheckLockedNeighbours(AtlasStore& store, const std::string& user, const StructureRef& ref,
                             GeometryFormat format, const std::filesystem::path& file) {
  std::vector<LockedNeighbour> neighbours;
  PBA_RETURN_IF_ERROR(store.LockedNeighbours(user, ref.project, ref.structure, &neighbours));
  for (const LockedNeighbour& n : neighbours) {
    OverlapMeasure m;
    const Status measured =
        MeasureOverlap({ToStructureFormat(format), file},
                       {ToStructureFormat(n.head.format), n.blob}, kOverlapVoxelMm, &m);
    if (!measured.ok()) {
      spdlog::warn("overlap of {} with {}: not measured: {}", ref.structure, n.head.structure,
                   measured.ToString());
      continue;
    }
    if (m.fraction_of_smaller() <= kOverlapTolerance) continue;
    char figures[160];
    std::snprintf(figures, sizeof figures,
                  "%.0f mm^3, %.1f %% of the smaller of the two (%.0f and %.0f mm^3); at most "
                  "%.0f %% is allowed",
                  m.overlap_mm3, 100 * m.fraction_of_smaller(), m.a_mm3, m.b_mm3,
                  100 * kOverlapTolerance);
    return Status::FailedPrecondition("the new geometry of '" + ref.structure + "' overlaps '" +
                                      n.head.structure + "', which " + n.holder +
                                      " holds locked, by " + figures +
                                      ": move the boundary, or agree on it with " + n.holder);
  }
  return Status::Ok();
}

}  // namespace pba
