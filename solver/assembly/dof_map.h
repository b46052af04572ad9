// DofMap: three displacement unknowns per node, split into free ones (solved
// for) and prescribed ones (eliminated: K_ff u_f = f_f - K_fp u_p).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "linear/linear_solver.h"

namespace pba {

class DofMap {
 public:
  explicit DofMap(int num_nodes) : free_(3 * num_nodes, 0), value_(3 * num_nodes, 0.0) {}

  // Prescribes component `c` (0..2) of `node` to `value` [m]; a later call wins.
  void Prescribe(int node, int c, double value) {
    free_[3 * node + c] = -1;
    value_[3 * node + c] = value;
  }
  // Numbers the free unknowns in dof order; call once, after every Prescribe().
  void Finalize();

  int num_dofs() const { return static_cast<int>(free_.size()); }
  int num_free() const { return num_free_; }
  // Free index of `dof`, or -1 when it is prescribed.
  int free_index(int dof) const { return free_[dof]; }
  bool prescribed(int dof) const { return free_[dof] < 0; }
  double prescribed_value(int dof) const { return value_[dof]; }

 private:
  std::vector<int> free_;  // before Finalize: 0 free, -1 prescribed
  std::vector<double> value_;
  int num_free_ = 0;
};

// The free unknowns' nodes and directions and the nodes' coordinates (rows
// of `nodes` [m]), for multigrid's rigid-body modes.
UnknownLayout MakeUnknownLayout(
    const DofMap& dofs, const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>& nodes);

}  // namespace pba
