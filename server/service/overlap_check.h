// The commit rule that keeps people out of each other's way: a structure's
// new geometry must not grow into a neighbour that someone else holds
// locked (they are working on it, and would find it changed under them). An
// overlap of more than kOverlapTolerance of the smaller of the two volumes,
// measured on kOverlapVoxelMm voxels (structure_overlap.h), is refused.
// Neighbours nobody holds, or the committer holds, are not checked: overlap
// between them is the committer's to resolve, and a build reports it.
// Derived structures (atlas/derived_structure.h) have no geometry of their
// own and are neither checked nor checked against.
#pragma once

#include <filesystem>
#include <string>

#include "pba/status.h"
#include "service/bounded_child.h"
#include "store/atlas_store.h"

namespace pba {

inline constexpr double kOverlapVoxelMm = 1.0;
inline constexpr double kOverlapTolerance = 0.01;

// kFailedPrecondition naming the neighbour, its holder and the overlap;
// a neighbour whose geometry cannot be read is skipped (logged). The
// measuring runs in a child process under `limits` (bounded_child.h); past
// them the answer is kFailedPrecondition saying which limit.
Status CheckLockedNeighbours(AtlasStore& store, const std::string& user, const StructureRef& ref,
                             StructureFormat format, const std::filesystem::path& file,
                             const ChildLimits& limits = {});

}  // namespace pba
