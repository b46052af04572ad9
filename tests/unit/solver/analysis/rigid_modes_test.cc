#include "analysis/rigid_modes.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <string>
#include <vector>

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

// The box and one more tetrahedron whose first corners are the box's
// nodes `shared` (none, an edge's two, a face's three) and whose others
// are new nodes above the box's top (z = 10 mm); region names given.
Mesh BoxAndATetrahedron(const std::vector<int>& shared) {
  Mesh mesh = Box();
  const int first_new = mesh.num_nodes();
  const int added = 4 - static_cast<int>(shared.size());
  mesh.nodes.conservativeResize(first_new + added, 3);
  const double top = 10e-3;
  const Eigen::RowVector3d far[4] = {{2e-3, 2e-3, top + 5e-3},
                                     {4e-3, 2e-3, top + 5e-3},
                                     {2e-3, 4e-3, top + 5e-3},
                                     {2e-3, 2e-3, top + 7e-3}};
  for (int i = 0; i < added; ++i) mesh.nodes.row(first_new + i) = far[i];
  std::array<int, 4> tet{};
  for (std::size_t i = 0; i < shared.size(); ++i) tet[i] = shared[i];
  for (int i = 0; i < added; ++i) tet[shared.size() + i] = first_new + i;
  mesh.tets.push_back(tet);
  mesh.region_names = {"Box", "Fragment"};
  mesh.element_region.assign(mesh.tets.size(), 0);
  mesh.element_region.back() = 1;
  return mesh;
}

// Two nodes of the box's top joined by an edge of its mesh, and a third
// that makes a face of one of its tetrahedra with them.
std::vector<int> TopEdgeAndFace(const Mesh& mesh) {
  for (const auto& tet : mesh.tets) {
    std::vector<int> on_top;
    for (int a : tet) {
      if (std::abs(mesh.nodes(a, 2) - 10e-3) < 1e-12) on_top.push_back(a);
    }
    if (on_top.size() == 3) return on_top;
  }
  return {};
}

TEST(LoosePiecesTest, OnePieceHeldIsFine) {
  const Mesh mesh = Box();
  int pieces = 0;
  const std::vector<int> piece = MeshPieces(mesh, &pieces);
  EXPECT_EQ(pieces, 1);
  EXPECT_EQ(piece.size(), mesh.tets.size());
  DofMap dofs(mesh.num_nodes());
  HoldSet(mesh, "bottom", {0, 1, 2}, &dofs);
  dofs.Finalize();
  EXPECT_EQ(DescribeLoosePieces(mesh, dofs), "");
}

TEST(LoosePiecesTest, AFragmentAndAHingedPieceAreNamedAndAFacePieceIsNot) {
  const std::vector<int> face = TopEdgeAndFace(Box());
  ASSERT_EQ(face.size(), 3u);
  struct Case {
    std::vector<int> shared;
    const char* how;  // "" : joined by a face, held with the box
  };
  const Case cases[] = {
      {{}, "touching nothing else"},
      {{face[0]}, "joined to the rest only by 1 node (an edge or a corner)"},
      {{face[0], face[1]}, "joined to the rest only by 2 nodes (an edge or a corner)"},
      {face, ""},
  };
  for (const Case& c : cases) {
    const Mesh mesh = BoxAndATetrahedron(c.shared);
    int pieces = 0;
    MeshPieces(mesh, &pieces);
    EXPECT_EQ(pieces, std::string(c.how).empty() ? 1 : 2) << c.how;
    DofMap dofs(mesh.num_nodes());
    HoldSet(mesh, "bottom", {0, 1, 2}, &dofs);
    dofs.Finalize();
    // The whole is held, so the whole-body check passes.
    EXPECT_EQ(DescribeFreeRigidModes(mesh, dofs), "");
    const std::string loose = DescribeLoosePieces(mesh, dofs);
    if (std::string(c.how).empty()) {
      EXPECT_EQ(loose, "");
      continue;
    }
    EXPECT_NE(loose.find("1 of the mesh's 2 pieces (elements joined by faces) are not held: "
                         "1 elements of Fragment (1)"),
              std::string::npos)
        << loose;
    EXPECT_NE(loose.find(c.how), std::string::npos) << loose;
    EXPECT_NE(loose.find("free: "), std::string::npos) << loose;
    // Held on its own, the fragment is fine.
    DofMap both(mesh.num_nodes());
    HoldSet(mesh, "bottom", {0, 1, 2}, &both);
    for (int a : mesh.tets.back()) {
      for (int k = 0; k < 3; ++k) both.Prescribe(a, k, 0.0);
    }
    both.Finalize();
    EXPECT_EQ(DescribeLoosePieces(mesh, both), "");
  }
}

}  // namespace
}  // namespace pba
