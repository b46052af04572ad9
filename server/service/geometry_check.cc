#include "service/geometry_check.h"

#include <stdlib.h>
#include <unistd.h>
#include <zlib.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>

#include "atlas/contours.h"
#include "atlas/derived_structure.h"
#include "atlas/label_volume_io.h"
#include "atlas/surface_io.h"
#include "core/atomic_write.h"
#include "core/format.h"

namespace pba {
namespace {

constexpr size_t kNiftiHeaderBytes = 348;

// The first `want` bytes of gzip data, or fewer if it is shorter or broken.
std::string Gunzip(std::string_view gz, size_t want) {
  std::string out(want, '\0');
  z_stream stream{};
  // 16 + MAX_WBITS: expect a gzip header.
  if (inflateInit2(&stream, 16 + MAX_WBITS) != Z_OK) return "";
  stream.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(gz.data()));
  stream.avail_in = static_cast<uInt>(std::min<size_t>(gz.size(), UINT32_MAX));
  stream.next_out = reinterpret_cast<Bytef*>(out.data());
  stream.avail_out = static_cast<uInt>(want);
  int result = Z_OK;
  while (stream.avail_out > 0 && result == Z_OK) result = inflate(&stream, Z_NO_FLUSH);
  out.resize(want - stream.avail_out);
  inflateEnd(&stream);
  return out;
}

// The data block through the solver's own reader (the one a structure set
// is composed with), from a temporary file as nifti1_io reads only files:
// an integer mask, at least one voxel non-zero, those voxels' centres within
// kMaxAtlasCoordinateMm of the origin.
// A temporary file, removed when it goes out of scope whatever happens
// (a failed read of a large upload once left its copy behind).
class TemporaryFile {
 public:
  explicit TemporaryFile(const std::string& suffix) {
    std::string pattern =
        (std::filesystem::temp_directory_path() / "pba-geometry-XXXXXX").string() + suffix;
    fd_ = mkstemps(pattern.data(), static_cast<int>(suffix.size()));
    if (fd_ >= 0) path_ = pattern;
  }
  ~TemporaryFile() {
    if (fd_ >= 0) close(fd_);
    std::error_code ignored;
    if (!path_.empty()) std::filesystem::remove(path_, ignored);
  }
  TemporaryFile(const TemporaryFile&) = delete;
  TemporaryFile& operator=(const TemporaryFile&) = delete;
  int fd() const { return fd_; }
  const std::string& path() const { return path_; }

 private:
  int fd_ = -1;
  std::string path_;
};

Status CheckNiftiData(const std::string& field, std::string_view content, bool gzipped) {
  LabelVolume volume;
  Status read;
  {
    const TemporaryFile file(gzipped ? ".nii.gz" : ".nii");
    if (file.fd() < 0) return Status::Io("cannot create a temporary file to read the NIfTI data");
    read = WriteAll(file.fd(), content.data(), content.size(), file.path());
    if (read.ok()) read = ReadNifti(file.path(), &volume);
  }
  if (!read.ok()) {
    if (read.code() != Status::Code::kInvalidArgument) return read;
    return Status::InvalidArgument(field, "NIfTI: " + read.message());
  }
  Eigen::Vector3d low = Eigen::Vector3d::Constant(INFINITY);
  Eigen::Vector3d high = Eigen::Vector3d::Constant(-INFINITY);
  for (int k = 0; k < volume.nz(); ++k) {
    for (int j = 0; j < volume.ny(); ++j) {
      for (int i = 0; i < volume.nx(); ++i) {
        if (volume.at(i, j, k) == 0) continue;
        const Eigen::Vector3d c = volume.VoxelCentreMm(i, j, k);
        low = low.cwiseMin(c);
        high = high.cwiseMax(c);
      }
    }
  }
  if (!(low.x() <= high.x())) {
    return Status::InvalidArgument(field, "NIfTI: the mask is empty (every voxel is 0)");
  }
  if (low.cwiseAbs().maxCoeff() > kMaxAtlasCoordinateMm ||
      high.cwiseAbs().maxCoeff() > kMaxAtlasCoordinateMm) {
    return Status::InvalidArgument(
        field, Format("NIfTI: the mask's voxels span (%g, %g, %g) to (%g, %g, %g) mm, farther "
                      "than 500 mm from the origin (a unit mistake?)",
                      low.x(), low.y(), low.z(), high.x(), high.y(), high.z()));
  }
  return Status::Ok();
}

// The header by hand first, for messages that say what the upload is not;
// then the data block.
Status CheckNifti(std::string_view field, std::string_view content) {
  const std::string_view whole = content;
  std::string inflated;
  const bool gzipped = content.size() >= 2 && static_cast<unsigned char>(content[0]) == 0x1f &&
                       static_cast<unsigned char>(content[1]) == 0x8b;
  if (gzipped) {
    inflated = Gunzip(content, kNiftiHeaderBytes);
    content = inflated;
  }
  if (content.size() < kNiftiHeaderBytes) {
    return Status::InvalidArgument(std::string(field),
                                   "is not NIfTI-1: shorter than the 348-byte header");
  }
  uint32_t sizeof_hdr = 0;
  std::memcpy(&sizeof_hdr, content.data(), 4);
  const uint32_t swapped = __builtin_bswap32(sizeof_hdr);
  if (sizeof_hdr != kNiftiHeaderBytes && swapped != kNiftiHeaderBytes) {
    return Status::InvalidArgument(std::string(field), "is not NIfTI-1: sizeof_hdr is not 348");
  }
  const std::string_view magic = content.substr(344, 4);
  if (magic == std::string_view("ni1\0", 4)) {
    // Its data is in a separate .img file, which an upload does not carry.
    return Status::InvalidArgument(std::string(field),
                                   "is the header of a NIfTI-1 .hdr/.img pair (magic \"ni1\"); "
                                   "upload a single-file NIfTI-1 (.nii or .nii.gz) instead");
  }
  if (magic != std::string_view("n+1\0", 4)) {
    return Status::InvalidArgument(std::string(field),
                                   "is not NIfTI-1: the magic is not \"n+1\" or \"ni1\"");
  }
  return CheckNiftiData(std::string(field), whole, gzipped);
}

Status CheckContoursJson(std::string_view field, std::string_view content) {
  Contours contours;
  return ParseContoursJson(content, std::string(field), &contours);
}

Status CheckSurface(std::string_view field, StructureFormat format, std::string_view content) {
  TriangleSurface surface;
  return ReadSurface(content, format, std::string(field), &surface);
}

// In this process: what the bounded child runs.
Status CheckContent(std::string_view field, StructureFormat format, std::string_view content) {
  switch (format) {
    case StructureFormat::kContours:
      return CheckContoursJson(field, content);
    case StructureFormat::kNifti:
      return CheckNifti(field, content);
    case StructureFormat::kStl:
    case StructureFormat::kObj:
    case StructureFormat::kVtk:
      return CheckSurface(field, format, content);
    case StructureFormat::kDerived: {
      DerivedStructure derived;
      return ParseDerivedStructure(content, "derived", std::string(field), &derived);
    }
  }
  return Status::InvalidArgument(std::string(field), "unknown geometry format");
}

}  // namespace

Status CheckGeometryContent(std::string_view field, StructureFormat format,
                            std::string_view content, const ChildLimits& limits) {
  if (content.empty()) return Status::InvalidArgument(std::string(field), "must not be empty");
  ChildOutcome outcome;
  PBA_RETURN_IF_ERROR(RunInBoundedChild(
      limits, [&](std::string*) { return CheckContent(field, format, content); }, &outcome));
  return OutcomeStatus(outcome, limits, std::string(field),
                       "the " + std::string(StructureFormatName(format)) + " file");
}

}  // namespace pba
