#include "analysis/rigid_modes.h"

#include <gtest/gtest.h>

#include "mesh/primitive_mesher.h"

namespace pba {
namespace {

Mesh Box() {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kBox;
  g.box.size_mm = {10, 10, 10};
  MeshSpec options;
  options.element_size_mm = 5;
  MeshStats stats;
  return BuildPrimitiveMesh(g, options, &stats);
}

void HoldSet(const Mesh& mesh, const std::string& set, std::initializer_list<int> components,
             DofMap* dofs) {
  for (int node : mesh.face_sets.at(set).nodes) {
    for (int c : components) dofs->Prescribe(node, c, 0.0);
  }
}

TEST(RigidModesTest, FixedFaceLeavesNothingFree) {
  const Mesh mesh = Box();
  DofMap dofs(mesh.num_nodes());
  HoldSet(mesh, "bottom", {0, 1, 2}, &dofs);
  dofs.Finalize();
  EXPECT_EQ(DescribeFreeRigidModes(mesh, dofs), "");
}

TEST(RigidModesTest, RollersLeaveNothingFree) {
  const Mesh mesh = Box();
  DofMap dofs(mesh.num_nodes());
  HoldSet(mesh, "bottom", {2}, &dofs);
  HoldSet(mesh, "x_min", {0}, &dofs);
  HoldSet(mesh, "y_min", {1}, &dofs);
  dofs.Finalize();
  EXPECT_EQ(DescribeFreeRigidModes(mesh, dofs), "");
}

TEST(RigidModesTest, OnlyNormalsHeldOnOneFaceLeavesInPlaneMotionFree) {
  const Mesh mesh = Box();
  DofMap dofs(mesh.num_nodes());
  HoldSet(mesh, "bottom", {2}, &dofs);
  dofs.Finalize();
  const std::string free = DescribeFreeRigidModes(mesh, dofs);
  EXPECT_NE(free.find("translation along x"), std::string::npos) << free;
  EXPECT_NE(free.find("translation along y"), std::string::npos) << free;
  EXPECT_NE(free.find("rotation about z"), std::string::npos) << free;
  EXPECT_EQ(free.find("translation along z"), std::string::npos) << free;
}

}  // namespace
}  // namespace pba
