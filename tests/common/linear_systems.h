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
