#include "assembly/dof_map.h"

namespace pba {

void DofMap::Finalize() {
  num_free_ = 0;
  for (int& f : free_) f = f < 0 ? -1 : num_free_++;
}

}  // namespace pba
