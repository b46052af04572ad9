// What `formulation: AUTO` does to every example scene: each scene is
// solved as written and with AUTO, and one Markdown row per scene says what
// AUTO chose, its estimate of the difference (from the coarse runs), the
// true difference between the two answers, and both wall times. The table
// in docs/scenes.md comes from this program (scripts/auto_table.sh).
//
// Usage: auto_formulation_table EXAMPLES_DIR [SCENE.yaml ...]
//   (no scenes: every *.yaml of EXAMPLES_DIR, sorted)
// The true difference is the largest relative difference over the results
// both summaries share (LargestRelativeDifference, the measure AUTO's own
// estimate uses), so the two columns compare like with like.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "codec/yaml_codec.h"
#include "convert/convert.h"
#include "pba/solve.h"
#include "pba/v1/scene.pb.h"
#include "scene/formulation.h"

namespace pba {
namespace {

namespace fs = std::filesystem;

std::string Choice(const Summary& summary) {
  std::string out;
  for (const ModelDecision& d : summary.decisions) {
    if (!out.empty()) out += "; ";
    out += d.aspect + ": " + d.decision;
  }
  return out.empty() ? "nothing to reduce" : out;
}

int Row(const fs::path& file) {
  v1::Scene message;
  codec::ParseError error;
  if (!codec::ReadYamlFile(file.string(), &message, &error)) {
    std::fprintf(stderr, "%s: %s\n", file.c_str(), error.ToString().c_str());
    return 1;
  }
  SceneSpec written;
  Status status = SceneFromProto(message, &written);
  if (!status.ok()) {
    std::fprintf(stderr, "%s: %s\n", file.c_str(), status.ToString().c_str());
    return 1;
  }
  written.formulation = Formulation::kAsWritten;
  SceneSpec automatic = written;
  automatic.formulation = Formulation::kAuto;
  const std::string name = file.stem().string();
  if (!ValidateScene(automatic).ok()) {
    std::printf("| %s | not available: %s | | | | |\n", name.c_str(),
                ValidateScene(automatic).message().c_str());
    std::fflush(stdout);
    return 0;
  }
  Solution full, reduced;
  status = SolveScene(written, {}, &full);
  if (status.ok()) status = SolveScene(automatic, {}, &reduced);
  if (!status.ok()) {
    std::fprintf(stderr, "%s: %s\n", file.c_str(), status.ToString().c_str());
    return 1;
  }
  const ReductionEstimate& r = reduced.summary.reduction;
  std::string quantity;
  const double truth = LargestRelativeDifference(full.summary, reduced.summary, &quantity);
  char estimate[160] = "nothing reduced";
  if (r.estimated) {
    std::snprintf(estimate, sizeof estimate, "%.3g %% (%s): %s", 100 * r.relative_difference,
                  r.quantity.empty() ? "-" : r.quantity.c_str(),
                  r.kept ? "reduced model kept" : "over the tolerance, solved as written");
  } else if (!r.note.empty() && r.note.find("nothing was reduced") == std::string::npos) {
    std::snprintf(estimate, sizeof estimate, "not estimated: solved as written");
  }
  std::printf("| %s | %s | %s | %.3g %% (%s) | %.3g s | %.3g s |\n", name.c_str(),
              Choice(reduced.summary).c_str(), estimate, 100 * truth,
              quantity.empty() ? "-" : quantity.c_str(), full.summary.wall_time_s,
              reduced.summary.wall_time_s);
  std::fflush(stdout);
  return 0;
}

}  // namespace
}  // namespace pba

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s EXAMPLES_DIR [SCENE.yaml ...]\n", argv[0]);
    return 2;
  }
  std::vector<fs::path> scenes;
  for (int i = 2; i < argc; ++i) scenes.emplace_back(argv[i]);
  if (scenes.empty()) {
    for (const auto& entry : fs::directory_iterator(argv[1])) {
      if (entry.path().extension() == ".yaml") scenes.push_back(entry.path());
    }
    std::sort(scenes.begin(), scenes.end());
  }
  std::printf(
      "| scene | what AUTO chose | estimated difference (coarse) | true difference | as written "
      "| AUTO |\n|---|---|---|---|---|---|\n");
  int failures = 0;
  for (const fs::path& scene : scenes) failures += pba::Row(scene);
  return failures == 0 ? 0 : 1;
}
