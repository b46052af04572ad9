// The checks of uploaded surfaces: closed, in bounds, with a volume; in
// each format a structure's surface travels in.
#include "service/geometry_check.h"

#include <gtest/gtest.h>
#include <stdlib.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "atlas/label_volume_io.h"
#include "common/yaml_bombs.h"

namespace pba {
namespace {

// A tetrahedron with corners 0, x, y, z (scaled by `s`), faces outwards.
constexpr double kCorners[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
constexpr int kFaces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};

std::string Obj(double s, int faces = 4) {
  std::string obj = "# a tetrahedron\n";
  for (const auto& c : kCorners) {
    obj += "v " + std::to_string(s * c[0]) + " " + std::to_string(s * c[1]) + " " +
           std::to_string(s * c[2]) + "\n";
  }
  for (int f = 0; f < faces; ++f) {
    obj += "f " + std::to_string(kFaces[f][0] + 1) + "/1 " + std::to_string(kFaces[f][1] + 1) +
           " " + std::to_string(kFaces[f][2] + 1) + "\n";
  }
  return obj;
}

std::string AsciiStl(double s) {
  std::string stl = "solid tet\n";
  for (const auto& f : kFaces) {
    stl += " facet normal 0 0 0\n  outer loop\n";
    for (int k : f) {
      stl += "   vertex " + std::to_string(s * kCorners[k][0]) + " " +
             std::to_string(s * kCorners[k][1]) + " " + std::to_string(s * kCorners[k][2]) + "\n";
    }
    stl += "  endloop\n endfacet\n";
  }
  return stl + "endsolid tet\n";
}

std::string BinaryStl(double s) {
  std::string stl(80, ' ');
  const uint32_t count = 4;
  stl.append(reinterpret_cast<const char*>(&count), 4);
  for (const auto& f : kFaces) {
    float record[12] = {};
    for (int k = 0; k < 3; ++k) {
      for (int c = 0; c < 3; ++c) record[3 + 3 * k + c] = static_cast<float>(s * kCorners[f[k]][c]);
    }
    stl.append(reinterpret_cast<const char*>(record), sizeof record);
    stl.append(2, '\0');
  }
  return stl;
}

std::string Vtk(const std::string& format = "ASCII") {
  std::string vtk =
      "# vtk DataFile Version 3.0\ntetrahedron\n" + format + "\nDATASET POLYDATA\nPOINTS 4 float\n";
  for (const auto& c : kCorners) {
    vtk += std::to_string(10 * c[0]) + " " + std::to_string(10 * c[1]) + " " +
           std::to_string(10 * c[2]) + "\n";
  }
  vtk += "POLYGONS 4 16\n";
  for (const auto& f : kFaces) {
    vtk += "3 " + std::to_string(f[0]) + " " + std::to_string(f[1]) + " " + std::to_string(f[2]) +
           "\n";
  }
  return vtk;
}

std::string Message(const Status& s) { return s.ToString(); }

TEST(GeometryCheckTest, ClosedSurfacesPassInEveryFormat) {
  EXPECT_TRUE(CheckGeometryContent("upload_id", StructureFormat::kObj, Obj(10)).ok());
  EXPECT_TRUE(CheckGeometryContent("upload_id", StructureFormat::kStl, AsciiStl(10)).ok());
  const Status binary = CheckGeometryContent("upload_id", StructureFormat::kStl, BinaryStl(10));
  EXPECT_TRUE(binary.ok()) << Message(binary);
  const Status vtk = CheckGeometryContent("upload_id", StructureFormat::kVtk, Vtk());
  EXPECT_TRUE(vtk.ok()) << Message(vtk);
}

TEST(GeometryCheckTest, OpenFlatFarOrUnreadableSurfacesAreNamed) {
  const Status open =
      CheckGeometryContent("upload_id", StructureFormat::kObj, Obj(10, 3) + "f 1 2 3\n");
  EXPECT_NE(Message(open).find("not a closed surface"), std::string::npos) << Message(open);
  const Status few = CheckGeometryContent("upload_id", StructureFormat::kObj, Obj(10, 3));
  EXPECT_NE(Message(few).find("at least four triangles"), std::string::npos) << Message(few);
  const Status flat = CheckGeometryContent("upload_id", StructureFormat::kObj, Obj(0));
  EXPECT_NE(Message(flat).find("no volume"), std::string::npos) << Message(flat);
  const Status far = CheckGeometryContent("upload_id", StructureFormat::kStl, AsciiStl(1000));
  EXPECT_NE(Message(far).find("500 mm"), std::string::npos) << Message(far);
  const Status index =
      CheckGeometryContent("upload_id", StructureFormat::kObj, "v 0 0 0\nf 1 2 3\n");
  EXPECT_NE(Message(index).find("line 2"), std::string::npos) << Message(index);
  const Status binary_vtk = CheckGeometryContent("upload_id", StructureFormat::kVtk, Vtk("BINARY"));
  EXPECT_NE(Message(binary_vtk).find("only ASCII"), std::string::npos) << Message(binary_vtk);
  const Status noise =
      CheckGeometryContent("upload_id", StructureFormat::kStl, "not a mesh at all");
  EXPECT_NE(Message(noise).find("neither binary STL"), std::string::npos) << Message(noise);
  for (const Status& s : {open, few, flat, far, index, binary_vtk, noise}) {
    EXPECT_EQ(s.code(), Status::Code::kInvalidArgument);
    EXPECT_EQ(s.field(), "upload_id");
  }
}

// The bytes of a NIfTI-1 file of a 4 x 3 x 2 volume of 1 mm voxels whose
// voxel (0, 0, 0) is centred at `origin`, with `fill` voxels set to 1.
std::string NiftiBytes(const Eigen::Vector3d& origin, int fill, const std::string& name) {
  LabelVolume volume({4, 3, 2}, origin, Eigen::Vector3d::Ones());
  for (int n = 0; n < fill; ++n) volume.mutable_labels()[n] = 1;
  const std::filesystem::path file = std::filesystem::path(testing::TempDir()) / name;
  EXPECT_TRUE(WriteNifti(volume, file).ok());
  std::ifstream in(file, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  std::filesystem::remove(file);
  return bytes.str();
}

TEST(GeometryCheckTest, NiftiMasksAreReadToTheirData) {
  const Eigen::Vector3d origin(-10, 5, 2);
  for (const char* name : {"mask.nii", "mask.nii.gz"}) {
    const Status ok =
        CheckGeometryContent("upload_id", StructureFormat::kNifti, NiftiBytes(origin, 5, name));
    EXPECT_TRUE(ok.ok()) << name << ": " << Message(ok);
  }
  const Status empty =
      CheckGeometryContent("upload_id", StructureFormat::kNifti, NiftiBytes(origin, 0, "e.nii"));
  EXPECT_NE(Message(empty).find("empty"), std::string::npos) << Message(empty);

  std::string whole = NiftiBytes(origin, 5, "t.nii");
  const Status truncated =
      CheckGeometryContent("upload_id", StructureFormat::kNifti, whole.substr(0, whole.size() - 7));
  EXPECT_NE(Message(truncated).find("truncated"), std::string::npos) << Message(truncated);

  const Status far = CheckGeometryContent("upload_id", StructureFormat::kNifti,
                                          NiftiBytes(Eigen::Vector3d(0, 0, 900), 5, "f.nii"));
  EXPECT_NE(Message(far).find("500 mm"), std::string::npos) << Message(far);

  // The same header made float32 (datatype 16, bitpix 32) over 24 floats,
  // one of them 0.5: not a label.
  std::string floats = whole.substr(0, 352);
  const int16_t datatype = 16, bitpix = 32;
  std::memcpy(&floats[70], &datatype, 2);
  std::memcpy(&floats[72], &bitpix, 2);
  for (int n = 0; n < 24; ++n) {
    const float value = n == 3 ? 0.5f : 1.0f;
    floats.append(reinterpret_cast<const char*>(&value), 4);
  }
  const Status fraction = CheckGeometryContent("upload_id", StructureFormat::kNifti, floats);
  EXPECT_NE(Message(fraction).find("0.5"), std::string::npos) << Message(fraction);

  // The header of a .hdr/.img pair: its data is not in the upload.
  std::string pair = whole.substr(0, 348);
  std::memcpy(&pair[344], "ni1", 4);
  const Status header_only = CheckGeometryContent("upload_id", StructureFormat::kNifti, pair);
  EXPECT_NE(Message(header_only).find(".hdr/.img"), std::string::npos) << Message(header_only);

  for (const Status& s : {empty, truncated, far, fraction, header_only}) {
    EXPECT_EQ(s.code(), Status::Code::kInvalidArgument);
    EXPECT_EQ(s.field(), "upload_id");
  }
}

// Contours whose polygons are nine levels of ten aliases: 10^9 points from
// about a kilobyte, which the checker once walked for minutes.
std::string AliasBombContours() {
  return "pixel_size_mm: 0.5\n" + yaml_bombs::AliasLevels("[[0, 0], [10, 0], [0, 10]]", "p") +
         "plates: [{z_mm: 0, polygons: *p9}]\n";
}

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

TEST(GeometryCheckTest, ContoursMadeOfAliasesAreRefusedAtOnce) {
  const auto start = std::chrono::steady_clock::now();
  const Status s =
      CheckGeometryContent("upload_id", StructureFormat::kContours, AliasBombContours());
  EXPECT_LT(SecondsSince(start), 5);
  EXPECT_EQ(s.code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(s.field(), "upload_id");
  EXPECT_NE(s.message().find("contours JSON: line 3: YAML aliases (*p0) are not accepted"),
            std::string::npos)
      << Message(s);
}

TEST(GeometryCheckTest, VtkAnnouncingAHugePolygonIsRefusedAtOnce) {
  // 125 bytes announcing a polygon of 2^28 points.
  const std::string vtk =
      "# vtk DataFile Version 3.0\nbomb\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n"
      "0 0 0 1 0 0 0 1 0\nPOLYGONS 1 268435457\n268435456 0 1 2\n";
  const auto start = std::chrono::steady_clock::now();
  const Status s = CheckGeometryContent("upload_id", StructureFormat::kVtk, vtk);
  EXPECT_LT(SecondsSince(start), 5);
  EXPECT_EQ(s.code(), Status::Code::kInvalidArgument);
  EXPECT_NE(s.message().find("a polygon of 268435456 points"), std::string::npos) << Message(s);
}

// A failed check leaves nothing in TMPDIR (a refused NIfTI once left its
// copy there for good).
TEST(GeometryCheckTest, AFailedNiftiCheckLeavesNothingInTmpdir) {
  const std::string whole = NiftiBytes(Eigen::Vector3d(-10, 5, 2), 5, "mask.nii");
  std::string pattern = (std::filesystem::path(testing::TempDir()) / "tmpdir-XXXXXX").string();
  ASSERT_NE(mkdtemp(pattern.data()), nullptr);
  const std::filesystem::path tmpdir = pattern;
  const char* old = getenv("TMPDIR");
  const std::string old_tmpdir = old != nullptr ? old : "";
  setenv("TMPDIR", tmpdir.c_str(), 1);

  const Status truncated =
      CheckGeometryContent("upload_id", StructureFormat::kNifti, whole.substr(0, whole.size() - 7));
  const bool empty_after_truncated = std::filesystem::is_empty(tmpdir);
  // Past its time limit the check is killed, its copy perhaps still open.
  ChildLimits no_time;
  no_time.time = std::chrono::milliseconds(1);
  const Status killed = CheckGeometryContent("upload_id", StructureFormat::kNifti, whole, no_time);
  const bool empty_after_killed = std::filesystem::is_empty(tmpdir);

  if (old != nullptr) {
    setenv("TMPDIR", old_tmpdir.c_str(), 1);
  } else {
    unsetenv("TMPDIR");
  }
  std::filesystem::remove_all(tmpdir);

  EXPECT_NE(Message(truncated).find("truncated"), std::string::npos) << Message(truncated);
  EXPECT_TRUE(empty_after_truncated);
  // (A fast machine may finish the check within the millisecond.)
  EXPECT_TRUE(killed.ok() || Message(killed).find("took longer than 0.001 s") != std::string::npos)
      << Message(killed);
  EXPECT_TRUE(empty_after_killed);
}

}  // namespace
}  // namespace pba
