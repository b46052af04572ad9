// QUASI_STATIC: not yet available.
#include "analysis/static_analysis.h"

namespace pba {

Status SolveQuasiStatic(const SceneSpec& scene, const Model& model, PhaseClock* clock,
                        Solution* solution, StaticResult* result) {
  return Status::InvalidArgument("analysis.type", "QUASI_STATIC is not available yet");
}

}  // namespace pba
