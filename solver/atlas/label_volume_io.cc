#include "atlas/label_volume_io.h"

#include <fcntl.h>
#include <nifti1_io.h>
#include <stdlib.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "core/atomic_write.h"
#include "core/format.h"

namespace pba {
namespace fs = std::filesystem;
namespace {

bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// Converts `count` values of type T (file order, i fastest over dims n),
// the first of them voxel `first`, into (*labels)[first, first + count),
// naming the first value that is not a label.
template <typename T>
Status ToLabels(const void* data, size_t count, size_t first, const std::array<int, 3>& n,
                const std::string& file, std::vector<uint16_t>* labels) {
  const T* values = static_cast<const T*>(data);
  for (size_t c = 0; c < count; ++c) {
    const T value = values[c];
    const double x = static_cast<double>(value);
    if (!(x >= 0 && x <= 65535 && std::floor(x) == x)) {
      const size_t v = first + c;
      const size_t i = v % n[0], j = (v / n[0]) % n[1], k = v / n[0] / n[1];
      std::ostringstream text;
      text.precision(17);
      text << +value;
      return Status::InvalidArgument(
          file, Format("value %s at voxel (%zu, %zu, %zu) is not a label (an integer in "
                       "0..65535)",
                       text.str().c_str(), i, j, k));
    }
    (*labels)[first + c] = static_cast<uint16_t>(x);
  }
  return Status::Ok();
}

using ToLabelsFunction = Status (*)(const void*, size_t, size_t, const std::array<int, 3>&,
                                    const std::string&, std::vector<uint16_t>*);

// The volume of file-order labels (dims n) whose index -> world (RAS, mm)
// map is world = origin + m * (i, j, k): reordered into RAS with positive
// spacing. m must be a signed permutation times positive scales.
Status AxisAlignedToVolume(const std::array<int, 3>& n, const Eigen::Matrix3d& m,
                           const Eigen::Vector3d& origin, const std::vector<uint16_t>& labels,
                           const std::string& file, LabelVolume* volume) {
  std::array<int, 3> axis{}, sign{};
  std::array<bool, 3> used{};
  for (int a = 0; a < 3; ++a) {
    const Eigen::Vector3d column = m.col(a);
    int w = 0;
    column.cwiseAbs().maxCoeff(&w);
    const double length = column.norm();
    if (!(length > 0) || !std::isfinite(length)) {
      return Status::InvalidArgument(file,
                                     Format("voxel axis %d has a zero or non-finite step", a));
    }
    for (int r = 0; r < 3; ++r) {
      if (r != w && std::abs(column[r]) > 1e-4 * length) {
        return Status::InvalidArgument(
            file, Format("oblique orientation: voxel axis %d steps (%g, %g, %g) mm; only "
                         "axis-aligned volumes (flips and axis permutations) are supported",
                         a, column[0], column[1], column[2]));
      }
    }
    if (used[w]) {
      return Status::InvalidArgument(file, "two voxel axes map to the same world axis");
    }
    used[w] = true;
    axis[a] = w;
    sign[a] = column[w] > 0 ? 1 : -1;
  }
  std::array<int, 3> dims{};
  Eigen::Vector3d spacing, corner;
  for (int a = 0; a < 3; ++a) {
    dims[axis[a]] = n[a];
    spacing[axis[a]] = std::abs(m(axis[a], a));
    corner[a] = sign[a] > 0 ? 0 : n[a] - 1;
  }
  LabelVolume out(dims, origin + m * corner, spacing);
  std::vector<uint16_t>& dst = out.mutable_labels();
  std::array<int, 3> o{};
  size_t v = 0;
  for (int k = 0; k < n[2]; ++k) {
    for (int j = 0; j < n[1]; ++j) {
      for (int i = 0; i < n[0]; ++i, ++v) {
        const int idx[3] = {i, j, k};
        for (int a = 0; a < 3; ++a) o[axis[a]] = sign[a] > 0 ? idx[a] : n[a] - 1 - idx[a];
        dst[out.Index(o[0], o[1], o[2])] = labels[v];
      }
    }
  }
  *volume = std::move(out);
  return Status::Ok();
}

constexpr size_t kReadPieceBytes = size_t{1} << 20;

// Voxel counts past kMaxLabelVolumeVoxels refused before any allocation.
Status CheckVoxelCount(const std::array<int, 3>& n, const std::string& file) {
  const double voxels = static_cast<double>(n[0]) * n[1] * n[2];
  if (voxels > static_cast<double>(kMaxLabelVolumeVoxels)) {
    return Status::InvalidArgument(
        file, Format("%d x %d x %d voxels: more than the %zu (512^3) a label volume may have", n[0],
                     n[1], n[2], kMaxLabelVolumeVoxels));
  }
  return Status::Ok();
}

// Whether `compressed` bytes can inflate to `wanted`: deflate expands at
// most 1032:1, so a header announcing more is a lie, refused before the
// data are read.
Status CheckInflatedSize(size_t wanted, uintmax_t compressed, const std::string& file) {
  if (static_cast<double>(wanted) > kMaxGzipRatio * static_cast<double>(compressed)) {
    return Status::InvalidArgument(
        file, Format("the header describes %zu bytes of data, more than %g times the %ju "
                     "bytes of the file (gzip cannot hold that much; truncated or forged)",
                     wanted, kMaxGzipRatio, compressed));
  }
  return Status::Ok();
}

Status CheckVolume(const LabelVolume& volume) {
  if (volume.num_voxels() == 0) return Status::InvalidArgument("volume", "empty label volume");
  if (!(volume.spacing_mm().minCoeff() > 0) || !volume.spacing_mm().allFinite() ||
      !volume.origin_mm().allFinite()) {
    return Status::InvalidArgument("volume", "spacing must be positive and origin finite");
  }
  return Status::Ok();
}

// ---- NIfTI-1 --------------------------------------------------------------

struct NiftiFree {
  void operator()(nifti_image* nim) const { nifti_image_free(nim); }
};

struct ZnzClose {
  void operator()(znzFile file) const { znzclose(file); }
};

}  // namespace

Status WriteNifti(const LabelVolume& volume, const fs::path& file) {
  PBA_RETURN_IF_ERROR(CheckVolume(volume));
  const std::string name = file.filename().string();
  const std::string suffix =
      EndsWith(name, ".nii.gz") ? ".nii.gz" : (EndsWith(name, ".nii") ? ".nii" : "");
  if (suffix.empty() || name == suffix) {
    return Status::InvalidArgument("file", file.string() +
                                               ": expected a name ending in .nii "
                                               "or .nii.gz");
  }
  nifti_set_debug_level(0);
  int dims[8] = {3, volume.nx(), volume.ny(), volume.nz(), 1, 1, 1, 1};
  std::unique_ptr<nifti_image, NiftiFree> nim(nifti_make_new_nim(dims, DT_UINT16, 1));
  if (!nim) return Status::Internal("nifti_make_new_nim failed");
  std::memcpy(nim->data, volume.labels().data(), volume.labels().size() * sizeof(uint16_t));
  const Eigen::Vector3d& h = volume.spacing_mm();
  const Eigen::Vector3d& o = volume.origin_mm();
  nim->dx = nim->pixdim[1] = static_cast<float>(h.x());
  nim->dy = nim->pixdim[2] = static_cast<float>(h.y());
  nim->dz = nim->pixdim[3] = static_cast<float>(h.z());
  nim->xyz_units = NIFTI_UNITS_MM;
  nim->scl_slope = 1;
  nim->scl_inter = 0;
  nim->qform_code = nim->sform_code = NIFTI_XFORM_SCANNER_ANAT;
  nim->quatern_b = nim->quatern_c = nim->quatern_d = 0;
  nim->qoffset_x = static_cast<float>(o.x());
  nim->qoffset_y = static_cast<float>(o.y());
  nim->qoffset_z = static_cast<float>(o.z());
  nim->qfac = 1;
  nim->qto_xyz = nifti_quatern_to_mat44(0, 0, 0, nim->qoffset_x, nim->qoffset_y, nim->qoffset_z,
                                        nim->dx, nim->dy, nim->dz, 1);
  nim->sto_xyz = nim->qto_xyz;
  const std::string description =
      volume.description().empty() ? "PBA label volume" : volume.description();
  std::strncpy(nim->descrip, description.c_str(), sizeof(nim->descrip) - 1);
  return AtomicWrite(file, suffix, [&](int, const std::string& temporary) {
    if (nifti_set_filenames(nim.get(), temporary.c_str(), 0, 1) != 0) {
      return Status::Io("NIfTI library rejected the file name " + temporary);
    }
    znzFile fp = nifti_image_write_hdr_img(nim.get(), 3, "wb");  // 3: data, leave open
    if (znz_isnull(fp)) return Status::Io("writing " + file.string() + " failed");
    if (znzclose(fp) != 0) return Status::Io("closing " + file.string() + " failed");
    return Status::Ok();
  });
}

Status ReadNifti(const fs::path& file, LabelVolume* volume) {
  const std::string path = file.string();
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) return Status::Io("missing " + path);
  nifti_set_debug_level(0);
  // The header through the library; the data read here, as the library
  // accepts data shorter than the header describes.
  std::unique_ptr<nifti_image, NiftiFree> nim(nifti_image_read(path.c_str(), 0));
  if (!nim) return Status::InvalidArgument(path, "not a readable NIfTI-1 header");
  if (nim->nx < 1 || nim->ny < 1 || nim->nz < 1 || nim->nt > 1 || nim->nu > 1 || nim->nv > 1 ||
      nim->nw > 1) {
    return Status::InvalidArgument(
        path, Format("dimensions %d x %d x %d x %d: expected a single 3-D volume", nim->nx, nim->ny,
                     nim->nz, nim->nt));
  }
  if ((nim->scl_slope != 0 && nim->scl_slope != 1) ||
      (nim->scl_slope != 0 && nim->scl_inter != 0)) {
    return Status::InvalidArgument(
        path, Format("scl_slope %g, scl_inter %g: a label image must not be scaled "
                     "(slope 0 or 1, intercept 0)",
                     nim->scl_slope, nim->scl_inter));
  }
  double scale = 1;  // to mm
  switch (nim->xyz_units) {
    case NIFTI_UNITS_UNKNOWN:
    case NIFTI_UNITS_MM:
      break;
    case NIFTI_UNITS_METER:
      scale = 1000;
      break;
    case NIFTI_UNITS_MICRON:
      scale = 1e-3;
      break;
    default:
      return Status::InvalidArgument(path, Format("xyz_units %d is not a length", nim->xyz_units));
  }
  Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  if (nim->sform_code > 0 || nim->qform_code > 0) {
    const mat44& a = nim->sform_code > 0 ? nim->sto_xyz : nim->qto_xyz;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) m(r, c) = a.m[r][c] * scale;
      origin[r] = a.m[r][3] * scale;
    }
  } else {
    m.diagonal() << nim->dx * scale, nim->dy * scale, nim->dz * scale;
  }
  const std::array<int, 3> n = {nim->nx, nim->ny, nim->nz};
  const size_t count = static_cast<size_t>(n[0]) * n[1] * n[2];  // dims are 16-bit: no overflow
  PBA_RETURN_IF_ERROR(CheckVoxelCount(n, path));
  const size_t want = count * static_cast<size_t>(std::max(nim->nbyper, 1));
  const bool gzipped = nifti_is_gzfile(nim->iname) != 0;
  const uintmax_t file_bytes = fs::file_size(nim->iname, ec);
  if (ec) return Status::Io("cannot read the size of " + std::string(nim->iname));
  // Checked against the bytes present before anything is allocated: a
  // 352-byte header can announce gigabytes.
  const size_t offset = static_cast<size_t>(std::max<int64_t>(nim->iname_offset, 0));
  if (!gzipped && file_bytes < offset + want) {
    return Status::InvalidArgument(
        path,
        Format("data holds %zu of the %zu bytes the header describes (truncated)",
               file_bytes > offset ? static_cast<size_t>(file_bytes - offset) : size_t{0}, want));
  }
  PBA_RETURN_IF_ERROR(CheckInflatedSize(want + offset, file_bytes, path));
  ToLabelsFunction convert = nullptr;
  switch (nim->datatype) {
    case DT_UINT8:
      convert = ToLabels<uint8_t>;
      break;
    case DT_INT8:
      convert = ToLabels<int8_t>;
      break;
    case DT_INT16:
      convert = ToLabels<int16_t>;
      break;
    case DT_UINT16:
      convert = ToLabels<uint16_t>;
      break;
    case DT_INT32:
      convert = ToLabels<int32_t>;
      break;
    case DT_UINT32:
      convert = ToLabels<uint32_t>;
      break;
    case DT_INT64:
      convert = ToLabels<int64_t>;
      break;
    case DT_UINT64:
      convert = ToLabels<uint64_t>;
      break;
    case DT_FLOAT32:
      convert = ToLabels<float>;
      break;
    case DT_FLOAT64:
      convert = ToLabels<double>;
      break;
    default:
      return Status::InvalidArgument(path,
                                     Format("datatype %d (%s) cannot hold labels", nim->datatype,
                                            nifti_datatype_string(nim->datatype)));
  }
  const size_t value_bytes = static_cast<size_t>(std::max(nim->nbyper, 1));
  std::unique_ptr<znzptr, ZnzClose> fp(znzopen(nim->iname, "rb", gzipped));
  if (znz_isnull(fp.get())) return Status::Io("cannot open " + std::string(nim->iname));
  // Read and converted in pieces: memory holds the labels and one piece of
  // the file's values, whatever their type.
  std::vector<uint16_t> labels(count);
  std::vector<uint8_t> piece(std::min(want, kReadPieceBytes / value_bytes * value_bytes));
  size_t done = 0;  // bytes
  if (znzseek(fp.get(), nim->iname_offset, SEEK_SET) >= 0) {
    while (done < want) {
      const size_t size = std::min(want - done, piece.size());
      const size_t got = znzread(piece.data(), 1, size, fp.get());
      const size_t values = got / value_bytes;
      if (nim->swapsize > 1 && nim->byteorder != nifti_short_order()) {
        nifti_swap_Nbytes(values, nim->swapsize, piece.data());
      }
      PBA_RETURN_IF_ERROR(convert(piece.data(), values, done / value_bytes, n, path, &labels));
      done += got;
      if (got < size) break;
    }
  }
  if (done != want) {
    return Status::InvalidArgument(
        path,
        Format("data holds %zu of the %zu bytes the header describes (truncated)", done, want));
  }
  PBA_RETURN_IF_ERROR(AxisAlignedToVolume(n, m, origin, labels, path, volume));
  volume->set_description(std::string(nim->descrip, strnlen(nim->descrip, sizeof(nim->descrip))));
  return Status::Ok();
}

// ---- NRRD -----------------------------------------------------------------

namespace {

std::string Trim(const std::string& s) {
  const size_t b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}

std::string Vector(const Eigen::Vector3d& v) {
  std::ostringstream s;
  s.precision(17);
  s << "(" << v.x() << "," << v.y() << "," << v.z() << ")";
  return s.str();
}

// "(a,b,c)" -> v; false when malformed.
bool ParseVector(const std::string& text, Eigen::Vector3d* v) {
  const std::string t = Trim(text);
  if (t.size() < 2 || t.front() != '(' || t.back() != ')') return false;
  std::stringstream in(t.substr(1, t.size() - 2));
  std::string part;
  int n = 0;
  while (std::getline(in, part, ',')) {
    if (n >= 3) return false;
    char* end = nullptr;
    const std::string p = Trim(part);
    (*v)[n++] = std::strtod(p.c_str(), &end);
    if (p.empty() || *end != '\0') return false;
  }
  return n == 3;
}

// Bytes per value of a NRRD type spelling, 0 when unsupported; *is_signed.
int NrrdTypeSize(const std::string& type, bool* is_signed) {
  static const std::map<std::string, std::pair<int, bool>> kTypes = {
      {"signed char", {1, true}},
      {"int8", {1, true}},
      {"int8_t", {1, true}},
      {"uchar", {1, false}},
      {"unsigned char", {1, false}},
      {"uint8", {1, false}},
      {"uint8_t", {1, false}},
      {"short", {2, true}},
      {"short int", {2, true}},
      {"signed short", {2, true}},
      {"signed short int", {2, true}},
      {"int16", {2, true}},
      {"int16_t", {2, true}},
      {"ushort", {2, false}},
      {"unsigned short", {2, false}},
      {"unsigned short int", {2, false}},
      {"uint16", {2, false}},
      {"uint16_t", {2, false}},
      {"int", {4, true}},
      {"signed int", {4, true}},
      {"int32", {4, true}},
      {"int32_t", {4, true}},
      {"uint", {4, false}},
      {"unsigned int", {4, false}},
      {"uint32", {4, false}},
      {"uint32_t", {4, false}}};
  const auto it = kTypes.find(type);
  if (it == kTypes.end()) return 0;
  *is_signed = it->second.second;
  return it->second.first;
}

// Inflates gzip (or zlib) data into exactly `want` bytes, in pieces, so
// that memory grows with the data actually there; more data than `want`
// are ignored.
Status Inflate(std::string_view in, size_t want, std::vector<uint8_t>* out,
               const std::string& file) {
  PBA_RETURN_IF_ERROR(CheckInflatedSize(want, in.size(), file));
  z_stream z{};
  if (inflateInit2(&z, 15 + 32) != Z_OK) return Status::Internal("inflateInit2 failed");
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(in.data()));
  z.avail_in = static_cast<uInt>(std::min<size_t>(in.size(), UINT32_MAX));
  out->clear();
  int rc = Z_OK;
  while (out->size() < want && rc == Z_OK) {
    const size_t old = out->size();
    const size_t piece = std::min(want - old, kReadPieceBytes);
    out->resize(old + piece);
    z.next_out = out->data() + old;
    z.avail_out = static_cast<uInt>(piece);
    rc = inflate(&z, Z_NO_FLUSH);
    out->resize(old + piece - z.avail_out);
    if (rc == Z_BUF_ERROR && z.avail_out == 0) rc = Z_OK;  // only the piece was full
  }
  inflateEnd(&z);
  if (out->size() < want) {
    return Status::InvalidArgument(
        file, Format("gzip data holds %zu of the %zu bytes the header describes (%s)", out->size(),
                     want, rc == Z_DATA_ERROR ? "corrupt" : "truncated"));
  }
  return Status::Ok();
}

}  // namespace

Status WriteNrrd(const LabelVolume& volume, const fs::path& file, NrrdEncoding encoding) {
  PBA_RETURN_IF_ERROR(CheckVolume(volume));
  const Eigen::Vector3d& h = volume.spacing_mm();
  std::string header = "NRRD0004\n";
  header += "# PBA label volume; format: http://teem.sourceforge.net/nrrd/format.html\n";
  header += "type: uint16\ndimension: 3\nspace: right-anterior-superior\n";
  if (!volume.description().empty()) {
    std::string content = volume.description();
    for (char& c : content) c = static_cast<unsigned char>(c) < 0x20 ? ' ' : c;
    header += "content: " + content + "\n";
  }
  header += Format("sizes: %d %d %d\n", volume.nx(), volume.ny(), volume.nz());
  header += "space directions: " + Vector({h.x(), 0, 0}) + " " + Vector({0, h.y(), 0}) + " " +
            Vector({0, 0, h.z()}) + "\n";
  header += "kinds: domain domain domain\nendian: little\n";
  header += std::string("encoding: ") + (encoding == NrrdEncoding::kGzip ? "gzip" : "raw") + "\n";
  header += "space origin: " + Vector(volume.origin_mm()) + "\n\n";
  std::vector<uint8_t> raw(volume.labels().size() * 2);
  for (size_t v = 0; v < volume.labels().size(); ++v) {
    raw[2 * v] = static_cast<uint8_t>(volume.labels()[v] & 0xff);
    raw[2 * v + 1] = static_cast<uint8_t>(volume.labels()[v] >> 8);
  }
  std::vector<uint8_t> data;
  if (encoding == NrrdEncoding::kGzip) {
    z_stream z{};
    if (deflateInit2(&z, 6, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) != Z_OK) {
      return Status::Internal("deflateInit2 failed");
    }
    data.resize(deflateBound(&z, raw.size()) + 32);
    z.next_in = raw.data();
    z.avail_in = static_cast<uInt>(raw.size());
    z.next_out = data.data();
    z.avail_out = static_cast<uInt>(data.size());
    const int rc = deflate(&z, Z_FINISH);
    data.resize(data.size() - z.avail_out);
    deflateEnd(&z);
    if (rc != Z_STREAM_END) return Status::Internal("gzip compression failed");
  } else {
    data = std::move(raw);
  }
  return AtomicWrite(file, ".nrrd", [&](int fd, const std::string& temporary) {
    PBA_RETURN_IF_ERROR(WriteAll(fd, header.data(), header.size(), temporary));
    return WriteAll(fd, data.data(), data.size(), temporary);
  });
}

Status ReadNrrd(const fs::path& file, LabelVolume* volume) {
  const std::string path = file.string();
  std::ifstream in(file, std::ios::binary);
  if (!in) return Status::Io("cannot open " + path);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto bad = [&](const std::string& what) { return Status::InvalidArgument(path, what); };
  if (text.compare(0, 7, "NRRD000") != 0) return bad("not a NRRD file (no NRRD000x magic)");
  // Header lines up to the first empty line; the data follow it.
  std::map<std::string, std::string> fields;
  size_t pos = text.find('\n');
  size_t data_start = std::string::npos;
  while (pos != std::string::npos && pos + 1 <= text.size()) {
    const size_t next = text.find('\n', pos + 1);
    if (next == std::string::npos) break;
    const std::string line = text.substr(pos + 1, next - pos - 1);
    pos = next;
    if (Trim(line).empty()) {
      data_start = next + 1;
      break;
    }
    if (line[0] == '#' || line.find(":=") != std::string::npos) continue;
    const size_t colon = line.find(": ");
    if (colon == std::string::npos) return bad("malformed header line '" + line + "'");
    fields[line.substr(0, colon)] = Trim(line.substr(colon + 2));
  }
  if (data_start == std::string::npos) return bad("header not ended by an empty line");
  const auto field = [&](const std::string& key) {
    const auto it = fields.find(key);
    return it == fields.end() ? std::string() : it->second;
  };
  if (!field("data file").empty() || !field("datafile").empty()) {
    return bad("detached data ('data file') is not supported");
  }
  for (const char* key : {"line skip", "lineskip", "byte skip", "byteskip"}) {
    if (!field(key).empty() && field(key) != "0")
      return bad(std::string(key) + " is not supported");
  }
  if (field("dimension") != "3") return bad("dimension '" + field("dimension") + "': expected 3");
  bool is_signed = false;
  const int bytes = NrrdTypeSize(field("type"), &is_signed);
  if (bytes == 0) return bad("type '" + field("type") + "' is not an integer label type");
  std::array<int, 3> n{};
  {
    std::istringstream sizes(field("sizes"));
    for (int& s : n) {
      if (!(sizes >> s) || s < 1) return bad("sizes '" + field("sizes") + "'");
    }
  }
  const std::string encoding = field("encoding");
  if (encoding != "raw" && encoding != "gzip" && encoding != "gz") {
    return bad("encoding '" + encoding + "': raw or gzip only");
  }
  const std::string endian = field("endian");
  if (bytes > 1 && endian != "little" && endian != "big") {
    return bad("endian '" + endian + "': little or big required");
  }

  // Index -> world map, in RAS.
  Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  const std::string space = field("space");
  if (!space.empty()) {
    Eigen::Vector3d flip;
    if (space == "right-anterior-superior" || space == "RAS") {
      flip << 1, 1, 1;
    } else if (space == "left-anterior-superior" || space == "LAS") {
      flip << -1, 1, 1;
    } else if (space == "left-posterior-superior" || space == "LPS") {
      flip << -1, -1, 1;
    } else {
      return bad("space '" + space + "': RAS, LAS or LPS only");
    }
    const std::string units = field("space units");
    if (!units.empty() && units != "\"mm\" \"mm\" \"mm\"") {
      return bad("space units " + units + ": mm only");
    }
    std::istringstream directions(field("space directions"));
    for (int a = 0; a < 3; ++a) {
      std::string token;
      Eigen::Vector3d d;
      if (!(directions >> token) || !ParseVector(token, &d)) {
        return bad("space directions '" + field("space directions") + "'");
      }
      m.col(a) = d.cwiseProduct(flip);
    }
    if (!field("space origin").empty()) {
      if (!ParseVector(field("space origin"), &origin)) {
        return bad("space origin '" + field("space origin") + "'");
      }
      origin = origin.cwiseProduct(flip);
    }
  } else {
    std::istringstream spacings(field("spacings"));
    for (int a = 0; a < 3; ++a) {
      if (!(spacings >> m(a, a))) return bad("neither space directions nor spacings");
    }
  }

  // Checked against the bytes present before anything is allocated.
  PBA_RETURN_IF_ERROR(CheckVoxelCount(n, path));
  const size_t count = static_cast<size_t>(n[0]) * n[1] * n[2];
  const size_t want = count * bytes;
  const std::string_view data = std::string_view(text).substr(data_start);
  std::vector<uint8_t> raw;
  if (encoding == "raw") {
    if (data.size() < want) {
      return bad(Format("data holds %zu of the %zu bytes the header describes (truncated)",
                        data.size(), want));
    }
    raw.assign(data.begin(), data.begin() + want);
  } else {
    PBA_RETURN_IF_ERROR(Inflate(data, want, &raw, path));
  }
  // To host order (little-endian hosts only: checked at compile time).
  static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "NRRD reader assumes little-endian");
  if (endian == "big" && bytes > 1) {
    for (size_t v = 0; v < count; ++v) std::reverse(&raw[v * bytes], &raw[v * bytes] + bytes);
  }
  std::vector<uint16_t> labels(count);
  Status converted;
  const void* d = raw.data();
  if (bytes == 1) {
    converted = is_signed ? ToLabels<int8_t>(d, count, 0, n, path, &labels)
                          : ToLabels<uint8_t>(d, count, 0, n, path, &labels);
  } else if (bytes == 2) {
    converted = is_signed ? ToLabels<int16_t>(d, count, 0, n, path, &labels)
                          : ToLabels<uint16_t>(d, count, 0, n, path, &labels);
  } else {
    converted = is_signed ? ToLabels<int32_t>(d, count, 0, n, path, &labels)
                          : ToLabels<uint32_t>(d, count, 0, n, path, &labels);
  }
  PBA_RETURN_IF_ERROR(converted);
  PBA_RETURN_IF_ERROR(AxisAlignedToVolume(n, m, origin, labels, path, volume));
  volume->set_description(field("content"));
  return Status::Ok();
}

Status ReadLabelVolume(const fs::path& file, const std::string& field, LabelVolume* volume) {
  const std::string name = file.filename().string();
  if (EndsWith(name, ".nii") || EndsWith(name, ".nii.gz")) return ReadNifti(file, volume);
  if (EndsWith(name, ".nrrd")) return ReadNrrd(file, volume);
  return Status::InvalidArgument(field,
                                 file.string() + " is not a label volume (.nii, .nii.gz or .nrrd)");
}

bool HasGzipMagic(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  unsigned char magic[2] = {0, 0};
  in.read(reinterpret_cast<char*>(magic), 2);
  return in.gcount() == 2 && magic[0] == 0x1f && magic[1] == 0x8b;
}

}  // namespace pba
