#include "atlas/label_volume_io.h"

#include <gtest/gtest.h>
#include <nifti1.h>
#include <unistd.h>
#include <zlib.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "common/bounded_run.h"

namespace pba {
namespace {

namespace fs = std::filesystem;

class LabelVolumeIoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("pba_label_volume_io_test_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  int FilesInDir() const {
    return static_cast<int>(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()));
  }
  fs::path dir_;
};

// Non-cubic dims, anisotropic spacing and an origin off zero, all exactly
// representable in float32 (NIfTI stores them so); labels over the uint16
// range.
LabelVolume SmallVolume() {
  LabelVolume v({7, 5, 3}, Eigen::Vector3d(-10.5, 20.25, 3), Eigen::Vector3d(0.75, 1.25, 2.5));
  for (int k = 0; k < v.nz(); ++k) {
    for (int j = 0; j < v.ny(); ++j) {
      for (int i = 0; i < v.nx(); ++i) v.set(i, j, k, static_cast<uint16_t>(i + 10 * j + 100 * k));
    }
  }
  v.set(6, 4, 2, 65535);
  v.set(0, 0, 0, 0);
  return v;
}

void ExpectSame(const LabelVolume& a, const LabelVolume& b) {
  EXPECT_EQ(a.dims(), b.dims());
  EXPECT_EQ(a.spacing_mm(), b.spacing_mm());
  EXPECT_EQ(a.origin_mm(), b.origin_mm());
  EXPECT_EQ(a.labels(), b.labels());
}

TEST_F(LabelVolumeIoTest, RoundTripsThroughNiftiAndNrrd) {
  const LabelVolume v = SmallVolume();
  for (const char* name : {"v.nii", "v.nii.gz"}) {
    SCOPED_TRACE(name);
    const Status written = WriteNifti(v, dir_ / name);
    ASSERT_TRUE(written.ok()) << written.ToString();
    LabelVolume read;
    const Status status = ReadNifti(dir_ / name, &read);
    ASSERT_TRUE(status.ok()) << status.ToString();
    ExpectSame(v, read);
  }
  for (const NrrdEncoding encoding : {NrrdEncoding::kRaw, NrrdEncoding::kGzip}) {
    const fs::path file = dir_ / (encoding == NrrdEncoding::kRaw ? "raw.nrrd" : "gzip.nrrd");
    SCOPED_TRACE(file.filename());
    const Status written = WriteNrrd(v, file, encoding);
    ASSERT_TRUE(written.ok()) << written.ToString();
    LabelVolume read;
    const Status status = ReadNrrd(file, &read);
    ASSERT_TRUE(status.ok()) << status.ToString();
    ExpectSame(v, read);
  }
  // Gzip did compress, and nothing but the four files is left.
  EXPECT_LT(fs::file_size(dir_ / "v.nii.gz"), fs::file_size(dir_ / "v.nii"));
  EXPECT_LT(fs::file_size(dir_ / "gzip.nrrd"), fs::file_size(dir_ / "raw.nrrd"));
  EXPECT_EQ(FilesInDir(), 4);
  EXPECT_FALSE(WriteNifti(v, dir_ / "v.img").ok());
}

// A NIfTI-1 single file written byte by byte: 348-byte header, 4 bytes of
// extension flags, data at 352. Dims 3 x 2 x 2, spacing (0.5, 2, 3) mm;
// file voxel (i, j, k) holds 1 + i + 3 j + 6 k.
nifti_1_header Header(int datatype, int bitpix) {
  nifti_1_header h;
  std::memset(&h, 0, sizeof h);
  h.sizeof_hdr = 348;
  h.dim[0] = 3;
  h.dim[1] = 3;
  h.dim[2] = 2;
  h.dim[3] = 2;
  for (int d = 4; d < 8; ++d) h.dim[d] = 1;
  h.datatype = static_cast<int16_t>(datatype);
  h.bitpix = static_cast<int16_t>(bitpix);
  h.pixdim[0] = 1;
  h.pixdim[1] = 0.5f;
  h.pixdim[2] = 2;
  h.pixdim[3] = 3;
  h.vox_offset = 352;
  h.scl_slope = 1;
  h.xyzt_units = NIFTI_UNITS_MM;
  std::memcpy(h.magic, "n+1", 4);
  return h;
}

template <typename T>
void WriteByHand(const fs::path& file, const nifti_1_header& h, const std::vector<T>& values) {
  std::ofstream out(file, std::ios::binary);
  out.write(reinterpret_cast<const char*>(&h), sizeof h);
  const char extension[4] = {0, 0, 0, 0};
  out.write(extension, 4);
  out.write(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
}

std::vector<int16_t> HandValues() {
  std::vector<int16_t> values(12);
  for (int v = 0; v < 12; ++v) values[v] = static_cast<int16_t>(1 + v);
  return values;
}

TEST_F(LabelVolumeIoTest, FlippedNiftiAxesReadIntoRas) {
  // LAS through the qform: a 180-degree turn about y (quatern_c = 1) with
  // qfac = -1 gives the rotation diag(-1, 1, 1).
  nifti_1_header las = Header(DT_INT16, 16);
  las.qform_code = NIFTI_XFORM_SCANNER_ANAT;
  las.quatern_c = 1;
  las.pixdim[0] = -1;  // qfac
  las.qoffset_x = 10;
  las.qoffset_y = -4;
  las.qoffset_z = 6;
  WriteByHand(dir_ / "las.nii", las, HandValues());
  // LPS through the sform (the qform unset).
  nifti_1_header lps = Header(DT_INT16, 16);
  lps.sform_code = NIFTI_XFORM_SCANNER_ANAT;
  const float srow_x[4] = {-0.5f, 0, 0, 10}, srow_y[4] = {0, -2, 0, -4}, srow_z[4] = {0, 0, 3, 6};
  std::memcpy(lps.srow_x, srow_x, sizeof srow_x);
  std::memcpy(lps.srow_y, srow_y, sizeof srow_y);
  std::memcpy(lps.srow_z, srow_z, sizeof srow_z);
  WriteByHand(dir_ / "lps.nii", lps, HandValues());

  for (const bool y_flipped : {false, true}) {
    SCOPED_TRACE(y_flipped ? "LPS sform" : "LAS qform");
    LabelVolume v;
    const Status status = ReadNifti(dir_ / (y_flipped ? "lps.nii" : "las.nii"), &v);
    ASSERT_TRUE(status.ok()) << status.ToString();
    EXPECT_EQ(v.dims(), (std::array<int, 3>{3, 2, 2}));
    EXPECT_EQ(v.spacing_mm(), Eigen::Vector3d(0.5, 2, 3));
    // The lowest x is the last file column: 10 - 2 * 0.5; likewise y.
    EXPECT_NEAR(v.origin_mm().x(), 9, 1e-6);
    EXPECT_NEAR(v.origin_mm().y(), y_flipped ? -6 : -4, 1e-6);
    EXPECT_NEAR(v.origin_mm().z(), 6, 1e-6);
    for (int k = 0; k < 2; ++k) {
      for (int j = 0; j < 2; ++j) {
        for (int i = 0; i < 3; ++i) {
          const int jj = y_flipped ? 1 - j : j;
          EXPECT_EQ(v.at(2 - i, jj, k), 1 + i + 3 * j + 6 * k) << i << " " << j << " " << k;
        }
      }
    }
  }
}

TEST_F(LabelVolumeIoTest, NiftiUnitsInMetresBecomeMillimetres) {
  nifti_1_header h = Header(DT_INT16, 16);
  h.xyzt_units = NIFTI_UNITS_METER;
  h.pixdim[1] = 0.0005f;
  h.pixdim[2] = 0.002f;
  h.pixdim[3] = 0.003f;
  WriteByHand(dir_ / "m.nii", h, HandValues());
  LabelVolume v;
  ASSERT_TRUE(ReadNifti(dir_ / "m.nii", &v).ok());
  EXPECT_NEAR(v.spacing_mm().x(), 0.5, 1e-6);
  EXPECT_NEAR(v.spacing_mm().z(), 3, 1e-6);
}

TEST_F(LabelVolumeIoTest, RejectsObliqueScaledAndNonLabelValues) {
  nifti_1_header oblique = Header(DT_INT16, 16);
  oblique.sform_code = NIFTI_XFORM_SCANNER_ANAT;
  const float c = std::cos(0.5f), s = std::sin(0.5f);
  const float srow_x[4] = {0.5f * c, -2 * s, 0, 0}, srow_y[4] = {0.5f * s, 2 * c, 0, 0};
  const float srow_z[4] = {0, 0, 3, 0};
  std::memcpy(oblique.srow_x, srow_x, sizeof srow_x);
  std::memcpy(oblique.srow_y, srow_y, sizeof srow_y);
  std::memcpy(oblique.srow_z, srow_z, sizeof srow_z);
  WriteByHand(dir_ / "oblique.nii", oblique, HandValues());
  LabelVolume v;
  Status status = ReadNifti(dir_ / "oblique.nii", &v);
  EXPECT_EQ(status.code(), Status::Code::kInvalidArgument);
  EXPECT_NE(status.message().find("oblique"), std::string::npos) << status.ToString();

  std::vector<float> floats(12, 2.0f);
  floats[7] = 2.5f;  // file voxel (1, 0, 1)
  WriteByHand(dir_ / "float.nii", Header(DT_FLOAT32, 32), floats);
  status = ReadNifti(dir_ / "float.nii", &v);
  EXPECT_EQ(status.code(), Status::Code::kInvalidArgument);
  EXPECT_NE(status.message().find("value 2.5 at voxel (1, 0, 1)"), std::string::npos)
      << status.ToString();
  floats[7] = 3;
  WriteByHand(dir_ / "float_ok.nii", Header(DT_FLOAT32, 32), floats);
  EXPECT_TRUE(ReadNifti(dir_ / "float_ok.nii", &v).ok());

  std::vector<int16_t> negative = HandValues();
  negative[2] = -3;
  WriteByHand(dir_ / "negative.nii", Header(DT_INT16, 16), negative);
  status = ReadNifti(dir_ / "negative.nii", &v);
  EXPECT_NE(status.message().find("value -3 "), std::string::npos) << status.ToString();

  nifti_1_header scaled = Header(DT_INT16, 16);
  scaled.scl_slope = 2;
  WriteByHand(dir_ / "scaled.nii", scaled, HandValues());
  status = ReadNifti(dir_ / "scaled.nii", &v);
  EXPECT_NE(status.message().find("scl_slope 2"), std::string::npos) << status.ToString();
}

TEST_F(LabelVolumeIoTest, TruncatedFilesAreRejected) {
  const LabelVolume v = SmallVolume();
  ASSERT_TRUE(WriteNifti(v, dir_ / "v.nii").ok());
  ASSERT_TRUE(WriteNifti(v, dir_ / "v.nii.gz").ok());
  ASSERT_TRUE(WriteNrrd(v, dir_ / "raw.nrrd", NrrdEncoding::kRaw).ok());
  ASSERT_TRUE(WriteNrrd(v, dir_ / "gzip.nrrd", NrrdEncoding::kGzip).ok());
  for (const char* name : {"v.nii", "v.nii.gz", "raw.nrrd", "gzip.nrrd"}) {
    SCOPED_TRACE(name);
    const fs::path file = dir_ / name;
    fs::resize_file(file, fs::file_size(file) - 40);
    LabelVolume read;
    const Status status = std::string(name).find(".nrrd") != std::string::npos
                              ? ReadNrrd(file, &read)
                              : ReadNifti(file, &read);
    EXPECT_EQ(status.code(), Status::Code::kInvalidArgument) << status.ToString();
  }
  // A header cut short.
  fs::resize_file(dir_ / "v.nii", 100);
  LabelVolume read;
  EXPECT_FALSE(ReadNifti(dir_ / "v.nii", &read).ok());
}

TEST_F(LabelVolumeIoTest, WritingIntoAMissingDirectoryFailsAndLeavesNothing) {
  const LabelVolume v = SmallVolume();
  const fs::path missing = dir_ / "missing";
  EXPECT_EQ(WriteNifti(v, missing / "v.nii.gz").code(), Status::Code::kIo);
  EXPECT_EQ(WriteNrrd(v, missing / "v.nrrd").code(), Status::Code::kIo);
  EXPECT_FALSE(fs::exists(missing));
  EXPECT_EQ(FilesInDir(), 0);
}

// A NRRD from another writer: LPS space, big-endian int16, raw.
TEST_F(LabelVolumeIoTest, ReadsLpsBigEndianNrrd) {
  std::string text =
      "NRRD0005\n# written by hand\ntype: short\ndimension: 3\n"
      "space: left-posterior-superior\nsizes: 3 2 2\n"
      "space directions: (-0.5,0,0) (0,-2,0) (0,0,3)\nkinds: domain domain domain\n"
      "endian: big\nencoding: raw\nspace origin: (-10,4,6)\nlabel:=anything\n\n";
  for (int16_t value : HandValues()) {
    text += static_cast<char>(value >> 8);
    text += static_cast<char>(value & 0xff);
  }
  std::ofstream(dir_ / "lps.nrrd", std::ios::binary) << text;
  LabelVolume v;
  const Status status = ReadNrrd(dir_ / "lps.nrrd", &v);
  ASSERT_TRUE(status.ok()) << status.ToString();
  // In RAS the directions are (0.5, 0, 0), (0, 2, 0): no flip; origin (10, -4, 6).
  EXPECT_EQ(v.spacing_mm(), Eigen::Vector3d(0.5, 2, 3));
  EXPECT_EQ(v.origin_mm(), Eigen::Vector3d(10, -4, 6));
  EXPECT_EQ(v.at(1, 1, 1), 1 + 1 + 3 + 6);
}

// ---- Hostile files: sizes a header announces but the file does not hold.
// Each read runs in a child that may map only 48 MiB more than the test
// (common/bounded_run.h): a reader that allocates what the header announces
// runs out of memory there instead of passing.

constexpr int64_t kReadBudget = int64_t{48} << 20;

// A header of dims nx x ny x nz and the given type, then `data_bytes` zeros.
std::string HostileNifti(int nx, int ny, int nz, int datatype, int bitpix, size_t data_bytes) {
  nifti_1_header h = Header(datatype, bitpix);
  h.dim[1] = static_cast<int16_t>(nx);
  h.dim[2] = static_cast<int16_t>(ny);
  h.dim[3] = static_cast<int16_t>(nz);
  std::string bytes(reinterpret_cast<const char*>(&h), sizeof h);
  bytes.append(4, '\0');  // no extensions
  bytes.append(data_bytes, '\0');
  return bytes;
}

void WriteGzip(const fs::path& file, const std::string& bytes) {
  gzFile out = gzopen(file.c_str(), "wb9");
  ASSERT_NE(out, nullptr);
  ASSERT_EQ(gzwrite(out, bytes.data(), static_cast<unsigned>(bytes.size())),
            static_cast<int>(bytes.size()));
  gzclose(out);
}

// The reader's status in a bounded child: kWorkTrue when it failed with
// kInvalidArgument and a message holding `expected`.
test::BoundedRunResult ReadFailsWith(const fs::path& file, const std::string& expected) {
  return test::RunBounded(kReadBudget, 20, [&] {
    LabelVolume v;
    const Status status = ReadLabelVolume(file, "file", &v);
    return status.code() == Status::Code::kInvalidArgument &&
           status.message().find(expected) != std::string::npos;
  });
}

TEST_F(LabelVolumeIoTest, NiftiHeaderAnnouncingMoreDataThanTheFileHoldsIsRefusedUpFront) {
  // 352 bytes announcing 500^3 float64 voxels (1 GB), then 12 bytes.
  std::ofstream(dir_ / "bomb.nii", std::ios::binary)
      << HostileNifti(500, 500, 500, DT_FLOAT64, 64, 12);
  EXPECT_EQ(ReadFailsWith(dir_ / "bomb.nii", "truncated"), test::kWorkTrue);
  LabelVolume v;
  const Status status = ReadNifti(dir_ / "bomb.nii", &v);
  EXPECT_NE(status.message().find("data holds 12 of the 1000000000 bytes"), std::string::npos)
      << status.ToString();
}

TEST_F(LabelVolumeIoTest, NiftiOverTheVoxelLimitIsRefused) {
  std::ofstream(dir_ / "big.nii", std::ios::binary)
      << HostileNifti(1024, 1024, 1024, DT_UINT8, 8, 16);
  EXPECT_EQ(ReadFailsWith(dir_ / "big.nii", "1024 x 1024 x 1024 voxels: more than the"),
            test::kWorkTrue);
}

TEST_F(LabelVolumeIoTest, GzipNiftiAnnouncingMoreThanDeflateCanHoldIsRefusedBeforeInflating) {
  // 400^3 float64 (512 MB) announced; a megabyte of zeros compresses to
  // about a kilobyte, far below what 512 MB would need.
  WriteGzip(dir_ / "bomb.nii.gz", HostileNifti(400, 400, 400, DT_FLOAT64, 64, 1 << 20));
  EXPECT_LT(fs::file_size(dir_ / "bomb.nii.gz"), 4096u);
  EXPECT_EQ(ReadFailsWith(dir_ / "bomb.nii.gz", "gzip cannot hold that much"), test::kWorkTrue);
}

TEST_F(LabelVolumeIoTest, GzipNiftiIsInflatedInPiecesNotPastTheAnnouncedSize) {
  // 300^3 uint8 (27 MB) present in full, then 200 MB of zeros the header
  // does not describe: read within the budget (labels 2 bytes a voxel and
  // one piece of the file's values), and the trailing data never inflated.
  std::string bytes = HostileNifti(300, 300, 300, DT_UINT8, 8, 300 * 300 * 300);
  bytes[sizeof(nifti_1_header) + 4 + 5] = 7;
  WriteGzip(dir_ / "long.nii.gz", bytes);
  EXPECT_EQ(test::RunBounded(int64_t{160} << 20, 20,
                             [&] {
                               LabelVolume v;
                               return ReadNifti(dir_ / "long.nii.gz", &v).ok() &&
                                      v.at(5, 0, 0) == 7;
                             }),
            test::kWorkTrue);
}

TEST_F(LabelVolumeIoTest, NrrdAnnouncingMoreDataThanItHoldsIsRefusedUpFront) {
  // int32, 500^3: 500 MB announced.
  std::ofstream(dir_ / "raw.nrrd", std::ios::binary)
      << "NRRD0004\ntype: int32\ndimension: 3\nsizes: 500 500 500\nspacings: 1 1 1\n"
         "endian: little\nencoding: raw\n\n0123456789";
  EXPECT_EQ(ReadFailsWith(dir_ / "raw.nrrd", "truncated"), test::kWorkTrue);
  // gzip: a few compressed bytes cannot inflate to 500 MB.
  std::string gz_bytes;
  {
    WriteGzip(dir_ / "data.gz", std::string(1 << 16, '\0'));
    std::ifstream in(dir_ / "data.gz", std::ios::binary);
    gz_bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  std::ofstream(dir_ / "gzip.nrrd", std::ios::binary)
      << "NRRD0004\ntype: int32\ndimension: 3\nsizes: 500 500 500\nspacings: 1 1 1\n"
         "endian: little\nencoding: gzip\n\n"
      << gz_bytes;
  EXPECT_EQ(ReadFailsWith(dir_ / "gzip.nrrd", "gzip cannot hold that much"), test::kWorkTrue);
}

}  // namespace
}  // namespace pba
