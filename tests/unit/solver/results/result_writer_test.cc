#include <gtest/gtest.h>
#include <hdf5.h>
#include <stdlib.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "pba/solve.h"

namespace pba {
namespace {
namespace fs = std::filesystem;

SceneSpec Scene() {
  SceneSpec s;
  s.name = "writer-test";
  s.geometry.kind = GeometrySpec::Kind::kBox;
  s.geometry.box.size_mm = {4, 4, 8};
  s.mesh.element_size_mm = 2;
  s.material.kind = MaterialSpec::Kind::kLinearElastic;
  s.material.linear_elastic = {3000, 0.45};
  BoundaryConditionSpec bottom{"bottom", BoundaryConditionSpec::Kind::kFixed, {}};
  BoundaryConditionSpec top{"top", BoundaryConditionSpec::Kind::kDisplacement, {}};
  top.displacement_mm[2] = -0.4;
  s.boundary_conditions = {bottom, top};
  return s;
}

std::string ReadAttribute(hid_t object, const char* name) {
  const hid_t attribute = H5Aopen(object, name, H5P_DEFAULT);
  if (attribute < 0) return "<missing>";
  const hid_t type = H5Aget_type(attribute);
  std::string value(H5Tget_size(type), '\0');
  H5Aread(attribute, type, value.data());
  H5Tclose(type);
  H5Aclose(attribute);
  return value.c_str();
}

std::vector<hsize_t> Dims(hid_t file, const char* path) {
  const hid_t dataset = H5Dopen2(file, path, H5P_DEFAULT);
  if (dataset < 0) return {};
  const hid_t space = H5Dget_space(dataset);
  std::vector<hsize_t> dims(H5Sget_simple_extent_ndims(space));
  H5Sget_simple_extent_dims(space, dims.data(), nullptr);
  H5Sclose(space);
  H5Dclose(dataset);
  return dims;
}

std::string ReadText(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// Two positively oriented 10-node tetrahedra sharing the face 1-2-3 and its
// mid-edge nodes (corners 0..4, then one node per edge), with made-up
// fields: enough to see the writer keep the ten columns.
Solution TwoQuadraticTets() {
  Solution s;
  s.nodes_per_element = 10;
  const double corners[5][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};
  for (const auto& c : corners) s.nodes_mm.insert(s.nodes_mm.end(), c, c + 3);
  // Mid-edge nodes 5..13 at the midpoints of these edges.
  const int edges[][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}, {2, 4}, {4, 1}, {4, 3}};
  for (const auto& e : edges) {
    for (int c = 0; c < 3; ++c) s.nodes_mm.push_back((corners[e[0]][c] + corners[e[1]][c]) / 2);
  }
  // Both in the order (0,1) (1,2) (2,0) (0,3) (1,3) (2,3) of their corners.
  s.tets = {0, 1, 2, 3, 5,  6,  7, 8, 9,  10,  //
            1, 4, 2, 3, 12, 11, 6, 9, 13, 10};
  const std::size_t nodes = s.nodes_mm.size() / 3, elements = 2;
  for (std::size_t i = 0; i < nodes; ++i) {
    s.displacement_mm.insert(s.displacement_mm.end(), {0, 0, -0.01 * static_cast<double>(i)});
  }
  s.stress_pa.assign(elements * 6, 10.0);
  s.strain.assign(elements * 6, 1e-3);
  s.von_mises_pa.assign(elements, 5.0);
  return s;
}

class ResultWriterTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::temp_directory_path() / "pba-writer.XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(ResultWriterTest, WritesFieldsWithUnitsAndAnXdmfThatPointsAtThem) {
  const SceneSpec scene = Scene();
  Solution solution;
  ASSERT_TRUE(SolveScene(scene, SolveOptions(), &solution).ok());
  ASSERT_TRUE(WriteResultFiles(scene, &solution, dir_).ok());
  EXPECT_EQ(solution.summary.phases.back().phase, "write");

  const hid_t file = H5Fopen((dir_ / "result.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  const hsize_t nodes = solution.nodes_mm.size() / 3, elements = solution.tets.size() / 4;
  EXPECT_EQ(Dims(file, "/mesh/nodes"), (std::vector<hsize_t>{nodes, 3}));
  EXPECT_EQ(Dims(file, "/mesh/tets"), (std::vector<hsize_t>{elements, 4}));
  EXPECT_EQ(Dims(file, "/fields/displacement"), (std::vector<hsize_t>{nodes, 3}));
  EXPECT_EQ(Dims(file, "/fields/stress"), (std::vector<hsize_t>{elements, 6}));
  EXPECT_EQ(Dims(file, "/fields/von_mises"), (std::vector<hsize_t>{elements}));
  EXPECT_EQ(ReadAttribute(file, "scene_name"), "writer-test");
  const hid_t tets = H5Dopen2(file, "/mesh/tets", H5P_DEFAULT);
  EXPECT_EQ(ReadAttribute(tets, "element_type"), "TET4");
  H5Dclose(tets);

  const hid_t displacement = H5Dopen2(file, "/fields/displacement", H5P_DEFAULT);
  EXPECT_EQ(ReadAttribute(displacement, "unit"), "mm");
  std::vector<double> values(solution.displacement_mm.size());
  H5Dread(displacement, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data());
  EXPECT_EQ(values, solution.displacement_mm);
  H5Dclose(displacement);
  const hid_t stress = H5Dopen2(file, "/fields/stress", H5P_DEFAULT);
  EXPECT_EQ(ReadAttribute(stress, "unit"), "Pa");
  EXPECT_EQ(ReadAttribute(stress, "components"), "xx yy zz yz xz xy");
  H5Dclose(stress);

  // Every HDF5 path the XDMF names exists in result.h5.
  std::ifstream in(dir_ / "result.xdmf");
  std::stringstream xdmf;
  xdmf << in.rdbuf();
  const std::string text = xdmf.str();
  const std::regex reference("result\\.h5:(/[a-z_/]+)");
  int references = 0;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), reference);
       it != std::sregex_iterator(); ++it) {
    EXPECT_FALSE(Dims(file, (*it)[1].str().c_str()).empty()) << (*it)[1].str();
    ++references;
  }
  EXPECT_GE(references, 4 + 12);  // mesh, displacement, von Mises, indicator, 12 components
  EXPECT_NE(text.find("Name=\"stress_zz\""), std::string::npos);
  H5Fclose(file);
}

// A nonlinear solve adds the finite-strain fields and one displacement
// record per load increment; the XDMF becomes a temporal collection over the
// increments (time = load factor) whose every reference exists.
TEST_F(ResultWriterTest, NonlinearSolveWritesFiniteStrainFieldsAndIncrements) {
  SceneSpec scene = Scene();
  scene.material.kind = MaterialSpec::Kind::kNeoHookean;
  scene.material.neo_hookean = {1000, 1e5};
  scene.analysis.type = AnalysisSpec::Type::kNonlinearStatic;
  Solution solution;
  const Status solved = SolveScene(scene, SolveOptions(), &solution);
  ASSERT_TRUE(solved.ok()) << solved.ToString();
  ASSERT_TRUE(WriteResultFiles(scene, &solution, dir_).ok());
  const hid_t file = H5Fopen((dir_ / "result.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  const hsize_t nodes = solution.nodes_mm.size() / 3, elements = solution.tets.size() / 4;
  const hsize_t steps = solution.step_load_factor.size();
  ASSERT_GE(steps, 1u);
  EXPECT_EQ(solution.step_load_factor.back(), 1.0);
  EXPECT_EQ(Dims(file, "/fields/pk2_stress"), (std::vector<hsize_t>{elements, 6}));
  EXPECT_EQ(Dims(file, "/fields/almansi_strain"), (std::vector<hsize_t>{elements, 6}));
  EXPECT_EQ(Dims(file, "/fields/jacobian"), (std::vector<hsize_t>{elements}));
  EXPECT_EQ(Dims(file, "/steps/load_factor"), (std::vector<hsize_t>{steps}));
  EXPECT_EQ(Dims(file, "/steps/displacement"), (std::vector<hsize_t>{steps * nodes, 3}));
  // The last increment's record is the final displacement.
  const hid_t records = H5Dopen2(file, "/steps/displacement", H5P_DEFAULT);
  std::vector<double> all(steps * nodes * 3);
  H5Dread(records, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, all.data());
  H5Dclose(records);
  EXPECT_EQ(std::vector<double>(all.end() - nodes * 3, all.end()), solution.displacement_mm);

  std::ifstream in(dir_ / "result.xdmf");
  std::stringstream xdmf;
  xdmf << in.rdbuf();
  const std::string text = xdmf.str();
  EXPECT_NE(text.find("CollectionType=\"Temporal\""), std::string::npos);
  std::size_t times = 0;
  for (auto at = text.find("<Time Value="); at != std::string::npos;
       at = text.find("<Time Value=", at + 1)) {
    ++times;
  }
  EXPECT_EQ(times, steps);
  const std::regex reference("result\\.h5:(/[a-z_/0-9]+)");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), reference);
       it != std::sregex_iterator(); ++it) {
    EXPECT_FALSE(Dims(file, (*it)[1].str().c_str()).empty()) << (*it)[1].str();
  }
  EXPECT_NE(text.find("Name=\"pk2_stress_zz\""), std::string::npos);
  EXPECT_NE(text.find("Name=\"jacobian\""), std::string::npos);
  H5Fclose(file);
}

// A 10-node solution keeps its ten columns in /mesh/tets (named TET10) and
// becomes XDMF's Tetrahedron_10, whose node order is PBA's.
// A model of several regions (an atlas's structures): each element's region
// in /mesh/region with the names in its attribute, the XDMF's cell scalar
// "region", and a surface per region in surfaces.glb; a model of one writes
// no region.
TEST_F(ResultWriterTest, RegionsAreWrittenAndDrawnApart) {
  Solution solution = TwoQuadraticTets();
  solution.region_names = {"Putamen", "Caudate nucleus"};
  solution.element_region = {1, 0};
  ASSERT_TRUE(WriteResultFiles(Scene(), &solution, dir_).ok());
  const hid_t file = H5Fopen((dir_ / "result.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  EXPECT_EQ(Dims(file, "/mesh/region"), (std::vector<hsize_t>{2}));
  const hid_t region = H5Dopen2(file, "/mesh/region", H5P_DEFAULT);
  std::vector<int64_t> values(2);
  H5Dread(region, H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data());
  EXPECT_EQ(values, solution.element_region);
  EXPECT_EQ(ReadAttribute(region, "names"), "Putamen\nCaudate nucleus\n");
  H5Dclose(region);
  H5Fclose(file);
  const std::string xdmf = ReadText(dir_ / "result.xdmf");
  EXPECT_NE(xdmf.find("<Attribute Name=\"region\" AttributeType=\"Scalar\" Center=\"Cell\">"),
            std::string::npos);
  EXPECT_NE(xdmf.find("result.h5:/mesh/region"), std::string::npos);
  const std::string glb = ReadText(dir_ / "surfaces.glb");
  EXPECT_EQ(glb.substr(0, 4), "glTF");
  EXPECT_NE(glb.find("\"name\":\"Putamen\""), std::string::npos);
  EXPECT_NE(glb.find("\"name\":\"Caudate nucleus\""), std::string::npos);

  Solution one = TwoQuadraticTets();
  fs::create_directories(dir_ / "one");
  ASSERT_TRUE(WriteResultFiles(Scene(), &one, dir_ / "one").ok());
  const hid_t plain = H5Fopen((dir_ / "one" / "result.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  EXPECT_TRUE(Dims(plain, "/mesh/region").empty());
  H5Fclose(plain);
  EXPECT_EQ(ReadText(dir_ / "one" / "result.xdmf").find("region"), std::string::npos);
  EXPECT_NE(ReadText(dir_ / "one" / "surfaces.glb").find("\"name\":\"body\""), std::string::npos);
}

TEST_F(ResultWriterTest, TenNodeSolutionWritesQuadraticCells) {
  const SceneSpec scene = Scene();
  Solution solution = TwoQuadraticTets();
  ASSERT_TRUE(WriteResultFiles(scene, &solution, dir_).ok());

  const hid_t file = H5Fopen((dir_ / "result.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  const hsize_t nodes = solution.nodes_mm.size() / 3;
  EXPECT_EQ(Dims(file, "/mesh/nodes"), (std::vector<hsize_t>{nodes, 3}));
  EXPECT_EQ(Dims(file, "/mesh/tets"), (std::vector<hsize_t>{2, 10}));
  EXPECT_EQ(Dims(file, "/fields/stress"), (std::vector<hsize_t>{2, 6}));
  EXPECT_EQ(Dims(file, "/fields/von_mises"), (std::vector<hsize_t>{2}));
  const hid_t tets = H5Dopen2(file, "/mesh/tets", H5P_DEFAULT);
  EXPECT_EQ(ReadAttribute(tets, "element_type"), "TET10");
  EXPECT_NE(ReadAttribute(tets, "components").find("(0,1) (1,2) (2,0) (0,3) (1,3) (2,3)"),
            std::string::npos);
  std::vector<int64_t> connectivity(solution.tets.size());
  H5Dread(tets, H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, connectivity.data());
  EXPECT_EQ(connectivity, solution.tets);
  H5Dclose(tets);

  const std::string text = ReadText(dir_ / "result.xdmf");
  EXPECT_NE(text.find("TopologyType=\"Tetrahedron_10\" NumberOfElements=\"2\" "
                      "NodesPerElement=\"10\""),
            std::string::npos)
      << text;
  EXPECT_EQ(text.find("TopologyType=\"Tetrahedron\""), std::string::npos);
  EXPECT_NE(text.find("<DataItem Dimensions=\"2 10\" NumberType=\"Int\" Precision=\"8\" "
                      "Format=\"HDF\">result.h5:/mesh/tets<"),
            std::string::npos);
  // Cell attributes have one value per element, not per 4 indices.
  EXPECT_NE(text.find("<DataItem Dimensions=\"2\" NumberType=\"Float\" Precision=\"8\" "
                      "Format=\"HDF\">result.h5:/fields/von_mises<"),
            std::string::npos);
  EXPECT_EQ(text.find("Dimensions=\"5 6\""), std::string::npos);  // 20 / 4 elements
  const std::regex reference("result\\.h5:(/[a-z_/]+)");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), reference);
       it != std::sregex_iterator(); ++it) {
    EXPECT_FALSE(Dims(file, (*it)[1].str().c_str()).empty()) << (*it)[1].str();
  }
  H5Fclose(file);
}

// A TET10 scene, solved: whatever the analysis fills in, the files agree
// with it (ten columns once the analyses hand back 10-node solutions).
TEST_F(ResultWriterTest, Tet10SceneWritesTheConnectivityItSolvedWith) {
  SceneSpec scene = Scene();
  scene.mesh.element = ElementType::kTet10;
  Solution solution;
  const Status solved = SolveScene(scene, SolveOptions(), &solution);
  ASSERT_TRUE(solved.ok()) << solved.ToString();
  ASSERT_TRUE(WriteResultFiles(scene, &solution, dir_).ok());
  const hid_t file = H5Fopen((dir_ / "result.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  const hsize_t per_element = static_cast<hsize_t>(solution.nodes_per_element);
  const hsize_t elements = solution.tets.size() / per_element;
  EXPECT_EQ(Dims(file, "/mesh/tets"), (std::vector<hsize_t>{elements, per_element}));
  EXPECT_EQ(Dims(file, "/fields/stress"), (std::vector<hsize_t>{elements, 6}));
  const std::string text = ReadText(dir_ / "result.xdmf");
  EXPECT_NE(text.find(per_element == 10 ? "TopologyType=\"Tetrahedron_10\""
                                        : "TopologyType=\"Tetrahedron\""),
            std::string::npos);
  H5Fclose(file);
}

// A connectivity that is neither 4- nor 10-node is a bug upstream, reported
// before any file is made.
TEST_F(ResultWriterTest, MalformedConnectivityIsAnInternalError) {
  const SceneSpec scene = Scene();
  Solution solution = TwoQuadraticTets();
  solution.nodes_per_element = 8;
  EXPECT_EQ(WriteResultFiles(scene, &solution, dir_).code(), Status::Code::kInternal);
  solution.nodes_per_element = 10;
  solution.tets.pop_back();
  EXPECT_EQ(WriteResultFiles(scene, &solution, dir_).code(), Status::Code::kInternal);
  EXPECT_FALSE(fs::exists(dir_ / "result.h5"));
}

TEST_F(ResultWriterTest, LeavesOutFieldsNotAskedFor) {
  SceneSpec scene = Scene();
  scene.outputs.stress = scene.outputs.strain = false;
  Solution solution;
  ASSERT_TRUE(SolveScene(scene, SolveOptions(), &solution).ok());
  ASSERT_TRUE(WriteResultFiles(scene, &solution, dir_).ok());
  const hid_t file = H5Fopen((dir_ / "result.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // the missing dataset is expected
  EXPECT_TRUE(Dims(file, "/fields/stress").empty());
  EXPECT_FALSE(Dims(file, "/fields/displacement").empty());
  H5Fclose(file);
}

// An explicit run's sensor samples go to sensors.csv, header first, 9
// significant digits, a value that is not finite an empty cell; a solution
// without sensors writes none.
TEST_F(ResultWriterTest, SensorSamplesGoToSensorsCsv) {
  const SceneSpec scene = Scene();
  Solution solution = TwoQuadraticTets();
  ASSERT_TRUE(WriteResultFiles(scene, &solution, dir_).ok());
  EXPECT_FALSE(fs::exists(dir_ / "sensors.csv"));

  solution.sensor_columns = {"time_s", "s1 pressure [Pa]", "s1 pressure filtered [Pa]",
                             "s1 speed [m/s]", "s1 speed filtered [m/s]"};
  solution.sensor_rows = {{0, 0, 0, 0, 0}, {1.23456789012e-6, 1500.5, 1400.25, 2.5, NAN}};
  ASSERT_TRUE(WriteResultFiles(scene, &solution, dir_).ok());
  EXPECT_EQ(ReadText(dir_ / "sensors.csv"),
            "time_s,s1 pressure [Pa],s1 pressure filtered [Pa],s1 speed [m/s],s1 speed "
            "filtered [m/s]\n"
            "0,0,0,0,0\n"
            "1.23456789e-06,1500.5,1400.25,2.5,\n");

  solution.sensor_rows.push_back({1});  // a short row is a bug upstream
  EXPECT_EQ(WriteResultFiles(scene, &solution, dir_).code(), Status::Code::kInternal);
}

TEST_F(ResultWriterTest, UnwritableDirectoryIsAnIoError) {
  const SceneSpec scene = Scene();
  Solution solution;
  ASSERT_TRUE(SolveScene(scene, SolveOptions(), &solution).ok());
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  const Status status = WriteResultFiles(scene, &solution, dir_ / "missing" / "deeper");
  EXPECT_EQ(status.code(), Status::Code::kIo);
  EXPECT_NE(status.message().find("result.h5"), std::string::npos);
}

}  // namespace
}  // namespace pba
