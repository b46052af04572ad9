#include "atlas/structure_overlap.h"

#include <stdlib.h>

#include <algorithm>
#include <cmath>
#include <system_error>
#include <vector>

#include "atlas/distance_transform.h"
#include "atlas/label_volume_io.h"

namespace pba {
namespace fs = std::filesystem;

double OverlapMeasure::fraction_of_smaller() const {
  const double smaller = std::min(a_mm3, b_mm3);
  return smaller > 0 ? overlap_mm3 / smaller : 0;
}

namespace {

// A directory under the temporary directory, removed with this object.
class ScratchDir {
 public:
  ScratchDir() {
    std::string pattern = (fs::temp_directory_path() / "pba-overlap-XXXXXX").string();
    if (::mkdtemp(pattern.data()) != nullptr) path_ = pattern;
  }
  ~ScratchDir() {
    std::error_code ignored;
    if (!path_.empty()) fs::remove_all(path_, ignored);
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

// Places `file` in the scratch set as `name` + extension: a hard link when
// it can (no copy of a large mask), else a copy. A NIfTI is named .nii.gz
// when gzip-compressed, else .nii: the reader goes by the name.
Status Place(const StructureGeometry& g, const fs::path& dir, const std::string& name,
             std::string* file_name) {
  *file_name = name + StructureFormatExtension(
                          g.format, g.format == StructureFormat::kNifti && HasGzipMagic(g.file));
  std::error_code ec;
  fs::create_hard_link(g.file, dir / *file_name, ec);
  if (ec) {
    ec.clear();
    fs::copy_file(g.file, dir / *file_name, ec);
  }
  if (ec) return Status::Io("cannot read " + g.file.string() + ": " + ec.message());
  return Status::Ok();
}

// The two geometries as a structure set in `scratch`, composed into one
// label volume; the name first in byte order keeps shared voxels, so
// `a_first` says which of the two wins them.
Status ComposePair(const StructureGeometry& a, const StructureGeometry& b, double voxel_mm,
                   const fs::path& scratch, bool a_first, ComposedAtlas* atlas) {
  for (const auto& [name, geometry] : {std::pair{"a", &a}, std::pair{"b", &b}}) {
    if (geometry->format == StructureFormat::kDerived) {
      return Status::InvalidArgument(
          name,
          "a derived structure has no shape of its own (it is made from the others when "
          "an atlas is composed)");
    }
  }
  StructureSet set;
  int colour = 1;
  for (const auto& [name, geometry] :
       {std::pair{a_first ? "a" : "b", &a}, std::pair{a_first ? "b" : "a", &b}}) {
    StructureEntry entry;
    entry.name = name;
    entry.format = geometry->format;
    entry.r = static_cast<uint8_t>(colour++);
    PBA_RETURN_IF_ERROR(Place(*geometry, scratch, name, &entry.file));
    set.structures.push_back(std::move(entry));
  }
  ComposeOptions options;
  options.voxel_size_mm = voxel_mm;
  options.force_volume = true;
  return ComposeStructureSet(scratch, set, options, atlas);
}

// The voxels of `inside` with a face-neighbour outside (or at the grid's edge).
std::vector<uint8_t> Boundary(const std::vector<uint8_t>& inside, const LabelVolume& grid) {
  std::vector<uint8_t> boundary(inside.size(), 0);
  for (int k = 0; k < grid.nz(); ++k) {
    for (int j = 0; j < grid.ny(); ++j) {
      for (int i = 0; i < grid.nx(); ++i) {
        const int64_t n = grid.Index(i, j, k);
        if (!inside[n]) continue;
        static constexpr int kFaces[6][3] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                             {0, -1, 0}, {0, 0, 1},  {0, 0, -1}};
        for (const auto& f : kFaces) {
          const int x = i + f[0], y = j + f[1], z = k + f[2];
          if (!grid.Contains(x, y, z) || !inside[grid.Index(x, y, z)]) {
            boundary[n] = 1;
            break;
          }
        }
      }
    }
  }
  return boundary;
}

}  // namespace

Status MeasureOverlap(const StructureGeometry& a, const StructureGeometry& b, double voxel_mm,
                      OverlapMeasure* measure) {
  ScratchDir scratch;
  if (scratch.path().empty()) return Status::Io("cannot create a scratch directory");
  ComposedAtlas atlas;
  PBA_RETURN_IF_ERROR(ComposePair(a, b, voxel_mm, scratch.path(), true, &atlas));
  *measure = OverlapMeasure();
  measure->voxel_mm = voxel_mm;
  measure->a_mm3 = atlas.structure_mm3["a"];
  measure->b_mm3 = atlas.structure_mm3["b"];
  for (const ComposedOverlap& o : atlas.overlaps) measure->overlap_mm3 += o.mm3;
  return Status::Ok();
}

Status CompareShapes(const StructureGeometry& a, const StructureGeometry& b, double voxel_mm,
                     ShapeComparison* comparison) {
  ComposedAtlas a_wins, b_wins;
  {
    ScratchDir scratch;
    if (scratch.path().empty()) return Status::Io("cannot create a scratch directory");
    PBA_RETURN_IF_ERROR(ComposePair(a, b, voxel_mm, scratch.path(), true, &a_wins));
  }
  {
    ScratchDir scratch;
    if (scratch.path().empty()) return Status::Io("cannot create a scratch directory");
    PBA_RETURN_IF_ERROR(ComposePair(a, b, voxel_mm, scratch.path(), false, &b_wins));
  }
  // Both compositions cover the same box with the same voxels (the grid
  // follows the union of the two), so each one's winner is whole in it.
  const LabelVolume& grid = *a_wins.volume;
  const uint16_t a_label = a_wins.colours.FindByName("a")->label;
  // In the second, b's geometry is named "a" (to win).
  const uint16_t b_label = b_wins.colours.FindByName("a")->label;
  std::vector<uint8_t> in_a(grid.num_voxels()), in_b(grid.num_voxels());
  int64_t count_a = 0, count_b = 0, shared = 0;
  for (int64_t n = 0; n < grid.num_voxels(); ++n) {
    in_a[n] = a_wins.volume->labels()[n] == a_label;
    in_b[n] = b_wins.volume->labels()[n] == b_label;
    count_a += in_a[n];
    count_b += in_b[n];
    shared += in_a[n] && in_b[n];
  }
  const double cell = voxel_mm * voxel_mm * voxel_mm;
  *comparison = ShapeComparison();
  comparison->overlap = {count_a * cell, count_b * cell, shared * cell, voxel_mm};
  comparison->dice = count_a + count_b > 0 ? 2.0 * shared / (count_a + count_b) : 1.0;
  if (count_a == 0 || count_b == 0) return Status::Ok();
  const std::vector<uint8_t> edge_a = Boundary(in_a, grid), edge_b = Boundary(in_b, grid);
  std::vector<double> to_a, to_b;
  SquaredDistanceTransform3d(edge_a, grid.nx(), grid.ny(), grid.nz(), &to_a);
  SquaredDistanceTransform3d(edge_b, grid.nx(), grid.ny(), grid.nz(), &to_b);
  double largest = 0, sum = 0;
  int64_t samples = 0;
  for (int64_t n = 0; n < grid.num_voxels(); ++n) {
    for (const auto& [edge, to_other] : {std::pair{&edge_a, &to_b}, std::pair{&edge_b, &to_a}}) {
      if (!(*edge)[n]) continue;
      const double d = std::sqrt((*to_other)[n]) * voxel_mm;
      largest = std::max(largest, d);
      sum += d;
      ++samples;
    }
  }
  comparison->hausdorff_mm = largest;
  comparison->mean_surface_distance_mm = samples > 0 ? sum / samples : 0;
  return Status::Ok();
}

}  // namespace pba
