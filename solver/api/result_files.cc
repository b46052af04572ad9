// The file-writing entries of pba/solve.h: ExportAbaqusInput (a scene
// resolved and meshed as for a solve, written by results/abaqus_writer.h) and
// WriteResultFiles (a solution's files with the scene's outputs, written by
// results/result_writer.h).
#include "pba/solve.h"
#include "results/abaqus_writer.h"
#include "results/result_writer.h"
#include "scene/problem.h"
#include "scene/unsolved.h"

namespace pba {

Status ExportAbaqusInput(const SceneSpec& scene, const std::filesystem::path& file) {
  PBA_RETURN_IF_ERROR(ValidateScene(scene));
  PBA_RETURN_IF_ERROR(RefuseUnsupportedFields(scene, "exported"));
  Problem problem;
  PBA_RETURN_IF_ERROR(BuildProblem(scene, BuildModelOptions(), &problem));
  return WriteAbaqusDeck(problem, file);
}

Status WriteResultFiles(const SceneSpec& scene, Solution* solution,
                        const std::filesystem::path& dir) {
  return WriteResults(scene.name, ResolveOutputs(scene), solution, dir);
}

}  // namespace pba
