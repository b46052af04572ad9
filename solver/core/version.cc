// SolverVersion (pba/solve.h), at the bottom of the numerical libraries: the
// atlas mesh cache keys its entries by it, and checkpoints and results
// record it.
#include "pba/solve.h"

namespace pba {

const char* SolverVersion() { return PBA_VERSION; }

}  // namespace pba
