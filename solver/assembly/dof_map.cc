#include "assembly/dof_map.h"

namespace pba {

void DofMap::Finalize() {
  num_free_ = 0;
  for (int& f : free_) f = f < 0 ? -1 : num_free_++;
}

UnknownLayout MakeUnknownLayout(
    const DofMap& dofs, const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>& nodes) {
  UnknownLayout layout;
  layout.dof_of_unknown.reserve(dofs.num_free());
  for (int dof = 0; dof < dofs.num_dofs(); ++dof) {
    if (!dofs.prescribed(dof)) layout.dof_of_unknown.push_back(dof);
  }
  layout.coordinates.assign(nodes.data(), nodes.data() + nodes.size());
  return layout;
}

}  // namespace pba
