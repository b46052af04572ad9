// `pba study convergence SCENE.yaml --quantity PATH ...`: a mesh-convergence
// study. One job per element size (mesh.element_size_mm; an atlas's region
// of interest scaled with it), submitted like a batch member (bounded
// parallelism, request ids, resumable through a state file beside the
// table), then one table: per mesh its size, elements, nodes, wall time and
// each quantity with its change from the previous mesh; per quantity the
// observed order, the Richardson extrapolate and the grid convergence index
// of the three finest meshes (study_math.h).
#pragma once

#include <string>
#include <vector>

#include "connection.h"

namespace CLI {
class App;
}

namespace pba::cli {

class CommandContext;

struct StudyArgs {
  std::string scene;                    // the base scene file
  std::vector<std::string> quantities;  // paths into each job's summary
  std::vector<double> sizes;            // element sizes [mm]; empty: from meshes and ratio
  int meshes = 3;                       // with ratio, from the scene's own size down
  double ratio = 1.41;                  // of successive element sizes, > 1
  int parallel = 2;                     // jobs in flight at most
  std::string out;           // the table as CSV; default SCENE's stem + ".convergence.csv"
  std::string snapshot;      // PROJECT/SNAPSHOT for an atlas scene; empty: none
  double tolerance_pct = 5;  // a change below it counts as converged [%]
  bool retry_failed = false;
  int ranks = 0;         // MPI processes per mesh's job
  bool dry_run = false;  // print each mesh's sizes, submit nothing
  double poll_s = 0.5;
};

int RunConvergenceStudy(Connection& connection, const StudyArgs& args);

// Adds `pba study convergence` to `app`.
void RegisterStudyCommands(CLI::App& app, CommandContext& context);

}  // namespace pba::cli
