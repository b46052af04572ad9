// Systems the linear-solver tests share: a block of soft tissue to assemble
// and a matrix of known inertia.
#pragma once

#include <Eigen/SparseCore>
#include <vector>

#include "assembly/assembler.h"
#include "assembly/dof_map.h"
#include "common/scene_builders.h"
#include "linear/linear_solver.h"
#include "material/linear_elastic.h"
#include "pba/scene.h"
#include "pba/status.h"
#include "scene/model_builder.h"

namespace pba::testing {

// A 20 x 20 x 30 mm block, bottom fixed, top pressed 1.5 mm (the quickstart
// and benchmark block), of linear elastic soft tissue (E = 3 kPa, nu = 0.45).
inline SceneSpec SoftBlock(double element_size_mm, AnalysisSpec::LinearSolver solver) {
  using K = BoundaryConditionSpec::Kind;
  SceneSpec s;
  s.name = "block";
  s.geometry.kind = GeometrySpec::Kind::kBox;
  s.geometry.box.size_mm = {20, 20, 30};
  s.mesh.element_size_mm = element_size_mm;
  s.material.kind = MaterialSpec::Kind::kLinearElastic;
  s.material.linear_elastic = {3000, 0.45};
  s.boundary_conditions = {Condition("bottom", K::kFixed),
                           Condition("top", K::kDisplacement, {0.0, 0.0, -1.5})};
  s.analysis.linear_solver = solver;
  return s;
}

// The small-strain stiffness and load of `model` (solver/ headers needed),
// all of it one isotropic material of E = 3 kPa and Poisson's ratio
// `poisson`.
inline Status AssembleSoftTissue(const Model& model, double poisson, LinearSystem* system) {
  return AssembleLinearSystem(
      model.mesh,
      ElasticityField::Uniform(IsotropicElasticity(3000, poisson), model.mesh.num_elements()),
      model.dofs, ColourElements(model.mesh), [](double) { return true; }, system, ThreadContext());
}

// The block's assembled stiffness and load, its unknowns' layout, and
// CHOLMOD's answer: what the linear-solver tests compare against.
struct BlockSystem {
  Model model;
  LinearSystem system;
  UnknownLayout layout;
  Eigen::VectorXd direct;  // CHOLMOD's answer
};

inline Status AssembleBlock(double element_size_mm, double poisson, BlockSystem* out) {
  const SceneSpec scene = SoftBlock(element_size_mm, AnalysisSpec::LinearSolver::kCholmod);
  PBA_RETURN_IF_ERROR(BuildModel(scene, &out->model));
  PBA_RETURN_IF_ERROR(AssembleSoftTissue(out->model, poisson, &out->system));
  out->layout = MakeUnknownLayout(out->model.dofs, out->model.mesh.nodes);
  const auto cholmod = CreateCholmodSolver(ThreadContext());
  PBA_RETURN_IF_ERROR(cholmod->Factorize(out->system.k));
  return cholmod->Solve(out->system.rhs, &out->direct);
}

// The 1D Laplacian (tridiagonal 2, -1) minus `shift` times the identity:
// eigenvalues 2 - shift - 2 cos(k pi / (n + 1)), k = 1..n.
inline Eigen::SparseMatrix<double> ShiftedLaplacian(int n, double shift) {
  std::vector<Eigen::Triplet<double>> entries;
  for (int i = 0; i < n; ++i) {
    entries.emplace_back(i, i, 2.0 - shift);
    if (i + 1 < n) {
      entries.emplace_back(i, i + 1, -1.0);
      entries.emplace_back(i + 1, i, -1.0);
    }
  }
  Eigen::SparseMatrix<double> a(n, n);
  a.setFromTriplets(entries.begin(), entries.end());
  a.makeCompressed();
  return a;
}

}  // namespace pba::testing
