// LabelVolume: a regular 3-D grid of uint16 labels (0 = background), the
// voxel form of an atlas.
//
// Coordinates are millimetres. Voxel (i, j, k) is centred at
//   origin_mm + (i * spacing_mm.x, j * spacing_mm.y, k * spacing_mm.z),
// so origin_mm is the centre of voxel (0, 0, 0), not a corner. Labels are
// stored x fastest: index = i + nx * (j + ny * k).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace pba {

class LabelVolume {
 public:
  LabelVolume() = default;
  // All voxels background. dims >= 1 each, spacing > 0 [mm].
  LabelVolume(const std::array<int, 3>& dims, const Eigen::Vector3d& origin_mm,
              const Eigen::Vector3d& spacing_mm);

  const std::array<int, 3>& dims() const { return dims_; }
  int nx() const { return dims_[0]; }
  int ny() const { return dims_[1]; }
  int nz() const { return dims_[2]; }
  int64_t num_voxels() const { return static_cast<int64_t>(labels_.size()); }
  const Eigen::Vector3d& origin_mm() const { return origin_mm_; }
  const Eigen::Vector3d& spacing_mm() const { return spacing_mm_; }
  double voxel_volume_mm3() const { return spacing_mm_.prod(); }

  int64_t Index(int i, int j, int k) const {
    return i + static_cast<int64_t>(dims_[0]) * (j + static_cast<int64_t>(dims_[1]) * k);
  }
  bool Contains(int i, int j, int k) const {
    return i >= 0 && j >= 0 && k >= 0 && i < dims_[0] && j < dims_[1] && k < dims_[2];
  }
  uint16_t at(int i, int j, int k) const { return labels_[Index(i, j, k)]; }
  void set(int i, int j, int k, uint16_t label) { labels_[Index(i, j, k)] = label; }
  const std::vector<uint16_t>& labels() const { return labels_; }
  std::vector<uint16_t>& mutable_labels() { return labels_; }

  // Centre of voxel (i, j, k) [mm].
  Eigen::Vector3d VoxelCentreMm(int i, int j, int k) const;
  // Continuous voxel coordinates of a point: integers at voxel centres.
  Eigen::Vector3d MmToVoxel(const Eigen::Vector3d& p_mm) const;
  // The voxel whose centre is nearest to p (each coordinate rounded half
  // up: floor(t + 0.5)); false when that voxel is outside the grid.
  bool NearestVoxel(const Eigen::Vector3d& p_mm, std::array<int, 3>* ijk) const;
  // Label of the nearest voxel, 0 outside the grid.
  uint16_t SampleNearest(const Eigen::Vector3d& p_mm) const;

  // What the file says the volume is (NIfTI's descrip, NRRD's content;
  // at most 79 characters): the synthetic atlas's volume carries
  // kSyntheticAtlasNotice, which lets it go without a label table.
  const std::string& description() const { return description_; }
  void set_description(std::string text) { description_ = std::move(text); }

 private:
  std::string description_;
  std::array<int, 3> dims_ = {0, 0, 0};
  Eigen::Vector3d origin_mm_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d spacing_mm_ = Eigen::Vector3d::Ones();
  std::vector<uint16_t> labels_;
};

// Voxel count per label: counts[l] for l in 0..65535 (size 65536).
std::vector<int64_t> CountLabels(const LabelVolume& volume);

struct LabelStats {
  int64_t voxel_count = 0;
  double volume_mm3 = 0;
  Eigen::Vector3d centroid_mm = Eigen::Vector3d::Zero();  // zero when empty
};

// Statistics of the voxels whose label is one of `labels` and, when `keep`
// is given, whose centre p [mm] satisfies keep(p) (e.g. one hemisphere).
LabelStats ComputeLabelStats(const LabelVolume& volume, const std::vector<uint16_t>& labels,
                             const std::function<bool(const Eigen::Vector3d&)>& keep = {});

}  // namespace pba
