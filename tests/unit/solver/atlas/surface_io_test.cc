// Closed surfaces read from STL, OBJ and VTK: welded, checked, and their
// enclosed volume.
#include "atlas/surface_io.h"

#include <gtest/gtest.h>

#include <chrono>
#include <string>

#include "common/bounded_run.h"

namespace pba {
namespace {

// The unit cube scaled by 10 as OBJ quads (fanned into two triangles each).
std::string ObjCube(bool drop_a_face = false) {
  std::string obj;
  for (int k = 0; k < 8; ++k) {
    obj += "v " + std::to_string(10 * (k & 1)) + " " + std::to_string(10 * ((k >> 1) & 1)) + " " +
           std::to_string(10 * ((k >> 2) & 1)) + "\n";
  }
  obj += "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\n";
  if (!drop_a_face) obj += "f 2 4 8 6\n";
  return obj;
}

// The same cube as ASCII STL triangles, every corner repeated per facet.
std::string StlCube() {
  static const int kQuads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                   {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  std::string stl = "solid cube\n";
  for (const auto& q : kQuads) {
    for (const auto& t : {std::array<int, 3>{q[0], q[1], q[2]}, {q[0], q[2], q[3]}}) {
      stl += "facet normal 0 0 0\nouter loop\n";
      for (int k : t) {
        stl += "vertex " + std::to_string(10 * (k & 1)) + " " +
               std::to_string(10 * ((k >> 1) & 1)) + " " + std::to_string(10 * ((k >> 2) & 1)) +
               "\n";
      }
      stl += "endloop\nendfacet\n";
    }
  }
  return stl + "endsolid cube\n";
}

TEST(SurfaceIoTest, CubesAreReadWeldedAndMeasured) {
  TriangleSurface obj, stl;
  ASSERT_TRUE(ReadSurface(ObjCube(), StructureFormat::kObj, "f", &obj).ok());
  EXPECT_EQ(obj.points.size(), 8u);
  EXPECT_EQ(obj.triangles.size(), 12u);
  EXPECT_DOUBLE_EQ(EnclosedVolume(obj), 1000);
  const Status s = ReadSurface(StlCube(), StructureFormat::kStl, "f", &stl);
  ASSERT_TRUE(s.ok()) << s.ToString();
  EXPECT_EQ(stl.points.size(), 8u);  // 36 corners welded
  EXPECT_EQ(stl.triangles.size(), 12u);
  EXPECT_DOUBLE_EQ(EnclosedVolume(stl), 1000);
}

TEST(SurfaceIoTest, OpenSurfacesAndOtherFormatsAreRefusedOnTheField) {
  TriangleSurface surface;
  const Status open = ReadSurface(ObjCube(true), StructureFormat::kObj, "structures[2]", &surface);
  EXPECT_EQ(open.code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(open.field(), "structures[2]");
  EXPECT_NE(open.message().find("OBJ: not a closed surface: 4 edges"), std::string::npos)
      << open.ToString();
  const Status vtk =
      ReadSurface("# vtk DataFile Version 3.0\nx\nBINARY\n", StructureFormat::kVtk, "f", &surface);
  EXPECT_NE(vtk.message().find("only ASCII"), std::string::npos) << vtk.ToString();
  EXPECT_FALSE(ReadSurface(ObjCube(), StructureFormat::kNifti, "f", &surface).ok());
}

// ---- Hostile VTK: counts a header announces but the file does not hold.
// Each read runs in a child that may map only 48 MiB more than the test
// (common/bounded_run.h): a reader that allocates what the file announces
// runs out of memory there instead of passing.

// The reader's status in a bounded child: kWorkTrue when it failed with
// kInvalidArgument on the field and a message holding `expected`.
test::BoundedRunResult VtkFailsWith(const std::string& vtk, const std::string& expected) {
  return test::RunBounded(int64_t{48} << 20, 20, [&] {
    TriangleSurface surface;
    const Status s = ReadSurface(vtk, StructureFormat::kVtk, "upload_id", &surface);
    return s.code() == Status::Code::kInvalidArgument && s.field() == "upload_id" &&
           s.message().find(expected) != std::string::npos;
  });
}

TEST(SurfaceIoTest, VtkAnnouncingMorePointsOrPolygonsThanItHoldsIsRefusedQuickly) {
  const std::string head = "# vtk DataFile Version 3.0\nbomb\nASCII\nDATASET POLYDATA\n";
  // A polygon of 2^28 points: a gigabyte of indices when allocated up front.
  const std::string big_polygon =
      head + "POINTS 3 float\n0 0 0 1 0 0 0 1 0\nPOLYGONS 1 268435457\n268435456 0 1 2\n";
  ASSERT_LT(big_polygon.size(), 140u);
  const auto start = std::chrono::steady_clock::now();
  EXPECT_EQ(
      VtkFailsWith(big_polygon, "VTK: a polygon of 268435456 points, but the file has only 3"),
      test::kWorkTrue);
  // Two billion points or polygons announced, a few present.
  EXPECT_EQ(VtkFailsWith(head + "POINTS 2000000000 float\n0 0 0 1 0 0\n",
                         "VTK: fewer POINTS than announced"),
            test::kWorkTrue);
  EXPECT_EQ(VtkFailsWith(head + "POINTS 3 float\n0 0 0 1 0 0 0 1 0\n"
                                "POLYGONS 2000000000 8000000000\n3 0 1 2\n",
                         "VTK: fewer POLYGONS than announced (1 of 2000000000)"),
            test::kWorkTrue);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5);
}

}  // namespace
}  // namespace pba
