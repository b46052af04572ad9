#include "service/overlap_check.h"

#include <spdlog/spdlog.h>

#include <cstdio>
#include <sstream>
#include <vector>

#include "atlas/structure_overlap.h"

namespace pba {

Status CheckLockedNeighbours(AtlasStore& store, const std::string& user, const StructureRef& ref,
                             StructureFormat format, const std::filesystem::path& file,
                             const ChildLimits& limits) {
  // A derived structure is made from the others when an atlas is composed:
  // it has no geometry of its own to grow into anyone's.
  if (format == StructureFormat::kDerived) return Status::Ok();
  std::vector<LockedNeighbour> neighbours;
  PBA_RETURN_IF_ERROR(store.LockedNeighbours(user, ref.project, ref.structure, &neighbours));
  std::erase_if(neighbours, [](const LockedNeighbour& n) {
    return n.head.format == StructureFormat::kDerived;
  });
  if (neighbours.empty()) return Status::Ok();
  // The measuring reads the new geometry, which may be hostile: in a
  // bounded child, which sends back the neighbours it could not measure as
  // lines of *skipped (it must not log: another thread may hold the
  // logger's lock at fork).
  const auto measure = [&](std::string* skipped) {
    for (const LockedNeighbour& n : neighbours) {
      OverlapMeasure m;
      const Status measured =
          MeasureOverlap({format, file}, {n.head.format, n.blob}, kOverlapVoxelMm, &m);
      if (!measured.ok()) {
        *skipped += n.head.structure + ": " + measured.ToString() + "\n";
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
  };
  ChildOutcome outcome;
  PBA_RETURN_IF_ERROR(RunInBoundedChild(limits, measure, &outcome));
  std::istringstream skipped(outcome.output);
  for (std::string line; std::getline(skipped, line);) {
    spdlog::warn("overlap of {} with {}: not measured", ref.structure, line);
  }
  if (outcome.end == ChildOutcome::End::kDone) return outcome.status;
  const Status bounded = OutcomeStatus(
      outcome, limits, "", "the overlap of '" + ref.structure + "' with its locked neighbours");
  return Status::FailedPrecondition(bounded.message());
}

}  // namespace pba
