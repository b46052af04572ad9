// LinearSolver: factorise a symmetric positive definite matrix once, solve
// for right-hand sides. One backend per file; CreateLinearSolver picks one.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <string>

#include "pba/scene.h"
#include "pba/status.h"

namespace pba {

class LinearSolver {
 public:
  virtual ~LinearSolver() = default;
  // Analyses and factorises `a` (both triangles stored; only the lower one is read).
  // A matrix that is not positive definite gives Status::Numerical.
  virtual Status Factorize(const Eigen::SparseMatrix<double>& a) = 0;
  virtual Status Solve(const Eigen::VectorXd& b, Eigen::VectorXd* x) = 0;
  // For people, e.g. "CHOLMOD supernodal Cholesky".
  virtual std::string Name() const = 0;
  // A fresh solver of the same kind (to hold a second factorisation).
  virtual std::unique_ptr<LinearSolver> NewOfSameKind() const = 0;
};

std::unique_ptr<LinearSolver> CreateLinearSolver(AnalysisSpec::LinearSolver kind);

// The backends (linear/cholmod_solver.cc, linear/eigen_ldlt_solver.cc).
std::unique_ptr<LinearSolver> CreateCholmodSolver();
std::unique_ptr<LinearSolver> CreateEigenLdltSolver();

}  // namespace pba
