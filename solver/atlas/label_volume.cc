#include "atlas/label_volume.h"

#include <algorithm>
#include <cmath>

namespace pba {

LabelVolume::LabelVolume(const std::array<int, 3>& dims, const Eigen::Vector3d& origin_mm,
                         const Eigen::Vector3d& spacing_mm)
    : dims_(dims), origin_mm_(origin_mm), spacing_mm_(spacing_mm) {
  labels_.assign(static_cast<size_t>(dims[0]) * dims[1] * dims[2], 0);
}

Eigen::Vector3d LabelVolume::VoxelCentreMm(int i, int j, int k) const {
  return origin_mm_ + Eigen::Vector3d(i, j, k).cwiseProduct(spacing_mm_);
}

Eigen::Vector3d LabelVolume::MmToVoxel(const Eigen::Vector3d& p_mm) const {
  return (p_mm - origin_mm_).cwiseQuotient(spacing_mm_);
}

bool LabelVolume::NearestVoxel(const Eigen::Vector3d& p_mm, std::array<int, 3>* ijk) const {
  const Eigen::Vector3d t = MmToVoxel(p_mm);
  for (int a = 0; a < 3; ++a) {
    const double r = std::floor(t[a] + 0.5);
    if (!(r >= 0 && r < dims_[a])) return false;  // also rejects NaN
    (*ijk)[a] = static_cast<int>(r);
  }
  return true;
}

uint16_t LabelVolume::SampleNearest(const Eigen::Vector3d& p_mm) const {
  std::array<int, 3> ijk;
  return NearestVoxel(p_mm, &ijk) ? at(ijk[0], ijk[1], ijk[2]) : uint16_t{0};
}

std::vector<int64_t> CountLabels(const LabelVolume& volume) {
  std::vector<int64_t> counts(65536, 0);
  for (uint16_t l : volume.labels()) ++counts[l];
  return counts;
}

LabelStats ComputeLabelStats(const LabelVolume& volume, const std::vector<uint16_t>& labels,
                             const std::function<bool(const Eigen::Vector3d&)>& keep) {
  std::vector<char> wanted(65536, 0);
  for (uint16_t l : labels) wanted[l] = 1;
  LabelStats stats;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int k = 0; k < volume.nz(); ++k) {
    for (int j = 0; j < volume.ny(); ++j) {
      for (int i = 0; i < volume.nx(); ++i) {
        if (!wanted[volume.at(i, j, k)]) continue;
        const Eigen::Vector3d p = volume.VoxelCentreMm(i, j, k);
        if (keep && !keep(p)) continue;
        ++stats.voxel_count;
        sum += p;
      }
    }
  }
  stats.volume_mm3 = stats.voxel_count * volume.voxel_volume_mm3();
  if (stats.voxel_count > 0) stats.centroid_mm = sum / static_cast<double>(stats.voxel_count);
  return stats;
}

}  // namespace pba
