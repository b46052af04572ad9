// Reassembling into a LinearSystem that already holds a matrix: on the same
// mesh and free unknowns the pattern is reused and filled in place, and the
// result is exactly (bit for bit) the matrix of a fresh assembly; under
// another set of constraints, or when the matrix was changed in between,
// the pattern is built anew, again exactly as a fresh assembly builds it.
#include "assembly/assembler.h"

#include <gtest/gtest.h>

#include <Eigen/SparseCore>
#include <string>
#include <vector>

#include "common/scene_builders.h"
#include "material/linear_elastic.h"
#include "scene/model_builder.h"

namespace pba {
namespace {

using K = BoundaryConditionSpec::Kind;
using testing::Condition;

// A 20 x 20 x 30 mm block of `element`s, bottom fixed, top pressed 1.5 mm.
Model Block(ElementType element) {
  SceneSpec s;
  s.name = "block";
  s.geometry.kind = GeometrySpec::Kind::kBox;
  s.geometry.box.size_mm = {20, 20, 30};
  s.mesh.element_size_mm = 5;
  s.mesh.element = element;
  s.material.kind = MaterialSpec::Kind::kLinearElastic;
  s.material.linear_elastic = {3000, 0.45};
  s.boundary_conditions = {Condition("bottom", K::kFixed),
                           Condition("top", K::kDisplacement, {0.0, 0.0, -1.5})};
  Model model;
  const Status built = BuildModel(s, &model);
  EXPECT_TRUE(built.ok()) << built.ToString();
  return model;
}

// The small-strain assembly of `mesh`'s element kind (with the prescribed
// values lifted, so that the right-hand side is not zero).
Status Assemble(const Mesh& mesh, const Matrix6d& d, const DofMap& dofs, LinearSystem* system) {
  const auto colours = ColourElements(mesh);
  const auto keep_going = [](double) { return true; };
  const ElasticityField elasticity = ElasticityField::Uniform(d, mesh.num_elements());
  return mesh.quadratic() ? AssembleLinearSystemTet10(mesh, elasticity, dofs, colours, keep_going,
                                                      system, ThreadContext())
         : mesh.hexahedral() ? AssembleLinearSystemHex8(mesh, elasticity, dofs, colours, keep_going,
                                                        system, ThreadContext())
                             : AssembleLinearSystem(mesh, elasticity, dofs, colours, keep_going,
                                                    system, ThreadContext());
}

// Same size, pattern (outer and inner indices) and values, compared exactly.
void ExpectIdentical(const LinearSystem& a, const LinearSystem& b, const std::string& label) {
  ASSERT_EQ(a.k.rows(), b.k.rows()) << label;
  ASSERT_EQ(a.k.cols(), b.k.cols()) << label;
  ASSERT_EQ(a.k.nonZeros(), b.k.nonZeros()) << label;
  ASSERT_TRUE(a.k.isCompressed() && b.k.isCompressed()) << label;
  const std::vector<int> outer_a(a.k.outerIndexPtr(), a.k.outerIndexPtr() + a.k.cols() + 1);
  const std::vector<int> outer_b(b.k.outerIndexPtr(), b.k.outerIndexPtr() + b.k.cols() + 1);
  EXPECT_EQ(outer_a, outer_b) << label;
  const std::vector<int> inner_a(a.k.innerIndexPtr(), a.k.innerIndexPtr() + a.k.nonZeros());
  const std::vector<int> inner_b(b.k.innerIndexPtr(), b.k.innerIndexPtr() + b.k.nonZeros());
  EXPECT_EQ(inner_a, inner_b) << label;
  const std::vector<double> values_a(a.k.valuePtr(), a.k.valuePtr() + a.k.nonZeros());
  const std::vector<double> values_b(b.k.valuePtr(), b.k.valuePtr() + b.k.nonZeros());
  EXPECT_EQ(values_a, values_b) << label;
  ASSERT_EQ(a.rhs.size(), b.rhs.size()) << label;
  EXPECT_TRUE(a.rhs == b.rhs) << label;
}

// `dofs` with one prescribed unknown freed and one free unknown prescribed:
// as many free unknowns, numbered differently.
DofMap SwapOneConstraint(const DofMap& dofs) {
  int freed = -1, fixed = -1;
  for (int dof = 0; dof < dofs.num_dofs(); ++dof) {
    if (dofs.prescribed(dof) && freed < 0) freed = dof;
    if (!dofs.prescribed(dof)) fixed = dof;  // the last free one
  }
  EXPECT_GE(freed, 0);
  EXPECT_GE(fixed, 0);
  DofMap swapped(dofs.num_dofs() / 3);
  for (int dof = 0; dof < dofs.num_dofs(); ++dof) {
    if ((dofs.prescribed(dof) && dof != freed) || dof == fixed) {
      swapped.Prescribe(dof / 3, dof % 3, dofs.prescribed(dof) ? dofs.prescribed_value(dof) : 0.0);
    }
  }
  swapped.Finalize();
  return swapped;
}

class ReassemblyTest : public ::testing::TestWithParam<ElementType> {};

TEST_P(ReassemblyTest, SameMeshAndUnknownsFillsThePatternInPlace) {
  const Model model = Block(GetParam());
  const Matrix6d soft = IsotropicElasticity(3000, 0.45);
  const Matrix6d stiff = IsotropicElasticity(7000, 0.3);
  LinearSystem reused;
  ASSERT_TRUE(Assemble(model.mesh, soft, model.dofs, &reused).ok());
  const int* inner = reused.k.innerIndexPtr();
  const double* values = reused.k.valuePtr();

  // A copy of the DofMap, as Newton's predictor uses: same free unknowns.
  const DofMap copy = model.dofs;
  ASSERT_TRUE(Assemble(model.mesh, stiff, copy, &reused).ok());
  LinearSystem fresh;
  ASSERT_TRUE(Assemble(model.mesh, stiff, model.dofs, &fresh).ok());
  ExpectIdentical(reused, fresh, "reassembled");
  // Filled in place: the same arrays, not a new matrix.
  EXPECT_EQ(reused.k.innerIndexPtr(), inner);
  EXPECT_EQ(reused.k.valuePtr(), values);
}

TEST_P(ReassemblyTest, OtherConstraintsBuildANewPattern) {
  const Model model = Block(GetParam());
  const Matrix6d d = IsotropicElasticity(3000, 0.45);
  const DofMap swapped = SwapOneConstraint(model.dofs);
  ASSERT_EQ(swapped.num_free(), model.dofs.num_free());

  LinearSystem reused;
  ASSERT_TRUE(Assemble(model.mesh, d, model.dofs, &reused).ok());
  ASSERT_TRUE(Assemble(model.mesh, d, swapped, &reused).ok());
  LinearSystem fresh;
  ASSERT_TRUE(Assemble(model.mesh, d, swapped, &fresh).ok());
  ExpectIdentical(reused, fresh, "same number of free unknowns, numbered differently");

  // Fewer free unknowns: one more unknown held.
  int first_free = 0;
  while (model.dofs.prescribed(first_free)) ++first_free;
  DofMap fewer = model.dofs;
  fewer.Prescribe(first_free / 3, first_free % 3, 0.0);
  fewer.Finalize();
  ASSERT_LT(fewer.num_free(), model.dofs.num_free());
  ASSERT_TRUE(Assemble(model.mesh, d, fewer, &reused).ok());
  LinearSystem fresh_fewer;
  ASSERT_TRUE(Assemble(model.mesh, d, fewer, &fresh_fewer).ok());
  ExpectIdentical(reused, fresh_fewer, "fewer free unknowns");
}

TEST_P(ReassemblyTest, AMatrixChangedInBetweenIsRebuilt) {
  const Model model = Block(GetParam());
  const Matrix6d d = IsotropicElasticity(3000, 0.45);
  LinearSystem reused;
  ASSERT_TRUE(Assemble(model.mesh, d, model.dofs, &reused).ok());
  // Move the last entry of the first column whose last row is not the
  // matrix's last to that last row: same size and number of entries, a
  // pattern that lacks an entry the elements need.
  SparseMatrix& k = reused.k;
  bool moved = false;
  for (int col = 0; col < k.cols() && !moved; ++col) {
    const int last = k.outerIndexPtr()[col + 1] - 1;
    if (last >= k.outerIndexPtr()[col] && k.innerIndexPtr()[last] < k.rows() - 1) {
      k.innerIndexPtr()[last] = static_cast<int>(k.rows()) - 1;
      moved = true;
    }
  }
  ASSERT_TRUE(moved);
  ASSERT_TRUE(Assemble(model.mesh, d, model.dofs, &reused).ok());
  LinearSystem fresh;
  ASSERT_TRUE(Assemble(model.mesh, d, model.dofs, &fresh).ok());
  ExpectIdentical(reused, fresh, "rebuilt after the pattern was changed");

  // A matrix replaced by another (here an empty one) is rebuilt too.
  reused.k = SparseMatrix(k.rows(), k.cols());
  ASSERT_TRUE(Assemble(model.mesh, d, model.dofs, &reused).ok());
  ExpectIdentical(reused, fresh, "rebuilt after the matrix was replaced");
}

INSTANTIATE_TEST_SUITE_P(Elements, ReassemblyTest,
                         ::testing::Values(ElementType::kTet4, ElementType::kTet10,
                                           ElementType::kHex8),
                         [](const ::testing::TestParamInfo<ElementType>& info) {
                           return std::string(info.param == ElementType::kTet4    ? "Tet4"
                                              : info.param == ElementType::kTet10 ? "Tet10"
                                                                                  : "Hex8");
                         });

}  // namespace
}  // namespace pba
