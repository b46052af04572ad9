#include "atlas/structure_overlap.h"

#include <stdlib.h>

#include <algorithm>
#include <fstream>
#include <system_error>

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

const char* Extension(StructureFormat format) {
  switch (format) {
    case StructureFormat::kContours:
      return ".json";
    case StructureFormat::kNifti:
      return ".nii.gz";
    case StructureFormat::kStl:
      return ".stl";
    case StructureFormat::kObj:
      return ".obj";
    case StructureFormat::kVtk:
      return ".vtk";
  }
  return "";
}

// Places `file` in the scratch set as `name` + extension: a hard link when
// it can (no copy of a large mask), else a copy. A NIfTI is named .nii.gz
// when gzip-compressed, else .nii: the reader goes by the name.
Status Place(const StructureGeometry& g, const fs::path& dir, const std::string& name,
             std::string* file_name) {
  *file_name = name + Extension(g.format);
  if (g.format == StructureFormat::kNifti) {
    // By its first bytes: uploads and blobs have no extension.
    std::ifstream in(g.file, std::ios::binary);
    unsigned char magic[2] = {0, 0};
    in.read(reinterpret_cast<char*>(magic), 2);
    const bool gz = in.gcount() == 2 && magic[0] == 0x1f && magic[1] == 0x8b;
    *file_name = name + (gz ? ".nii.gz" : ".nii");
  }
  std::error_code ec;
  fs::create_hard_link(g.file, dir / *file_name, ec);
  if (ec) {
    ec.clear();
    fs::copy_file(g.file, dir / *file_name, ec);
  }
  if (ec) return Status::Io("cannot read " + g.file.string() + ": " + ec.message());
  return Status::Ok();
}

}  // namespace

Status MeasureOverlap(const StructureGeometry& a, const StructureGeometry& b, double voxel_mm,
                      OverlapMeasure* measure) {
  ScratchDir scratch;
  if (scratch.path().empty()) return Status::Io("cannot create a scratch directory");
  StructureSet set;
  int colour = 1;
  for (const auto& [name, geometry] : {std::pair{"a", &a}, std::pair{"b", &b}}) {
    StructureEntry entry;
    entry.name = name;
    entry.format = geometry->format;
    entry.r = static_cast<uint8_t>(colour++);
    PBA_RETURN_IF_ERROR(Place(*geometry, scratch.path(), name, &entry.file));
    set.structures.push_back(std::move(entry));
  }
  ComposeOptions options;
  options.voxel_size_mm = voxel_mm;
  options.force_volume = true;
  ComposedAtlas atlas;
  PBA_RETURN_IF_ERROR(ComposeStructureSet(scratch.path(), set, options, &atlas));
  *measure = OverlapMeasure();
  measure->voxel_mm = voxel_mm;
  measure->a_mm3 = atlas.structure_mm3["a"];
  measure->b_mm3 = atlas.structure_mm3["b"];
  for (const ComposedOverlap& o : atlas.overlaps) measure->overlap_mm3 += o.mm3;
  return Status::Ok();
}

}  // namespace pba
