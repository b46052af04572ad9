// Speed against the peer: the same finite-strain model solved by PBA and by
// CalculiX (ccx, OMP_NUM_THREADS=2). A neo-Hookean 10 mm cube (mu = 1 kPa,
// K = 100 kPa), bottom fixed, top pressed 3 mm (30 %) and held sideways, in
// 10 increments, on 16^3 and 24^3 bricks. HEX8_FULL is CalculiX's C3D8, so
// both codes solve the same discrete problem and the top reactions must
// agree to 1e-5 (calculix_peer_test allows 2e-5 at finite strain); the
// HEX8 (mean-dilatation) rows give PBA's time at its own, unlocked answer
// beside the same ccx run. A benchmark, not a test: scripts/bench.sh runs it
// for docs/performance.md.
#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <map>
#include <string>

#include "common/calculix.h"
#include "common/scene_builders.h"
#include "common/subprocess.h"
#include "pba/solve.h"

namespace pba {
namespace {

// The agreement the HEX8_FULL rows must reach; a larger difference is
// flagged in the row's label.
constexpr double kAgreement = 1e-5;

// The shared pressed cube (common/scene_builders.h), the top's reaction kept.
SceneSpec PressedCube(int cells, ElementType element) {
  SceneSpec s = testing::NeoHookeanCube(element, 10.0 / cells, 1e5, 3.0, 10,
                                        AnalysisSpec::LinearSolver::kAuto);
  s.name = "bench-peer-cube";
  s.outputs.reaction_sets = {"top"};
  return s;
}

struct PeerRun {
  double seconds = 0;
  double top_force_n = 0;  // z component of the reaction on the top face
};

// ccx's answer per mesh (cells per edge), kept for the HEX8 row of the same
// mesh: the deck of a HEX8 scene is the same C3D8 model.
std::map<int, PeerRun>& PeerRuns() {
  static std::map<int, PeerRun> runs;
  return runs;
}

// Exports `scene`, runs ccx on it; false (with `error`) if that failed.
bool RunPeer(const SceneSpec& scene, PeerRun* run, std::string* error) {
  const std::string ccx = testing::FindCcx();
  if (ccx.empty()) {
    *error = "ccx not found; scripts/deps.sh installs calculix-ccx";
    return false;
  }
  testing::TempDir dir;
  const Status exported = ExportAbaqusInput(scene, dir.path() / "model.inp");
  if (!exported.ok()) {
    *error = exported.ToString();
    return false;
  }
  const testing::CcxRun ccx_run =
      testing::RunCcx(ccx, dir.path(), "model", 2, std::chrono::seconds(1800));
  if (ccx_run.process.exit_code != 0) {
    *error = "ccx exited with " + std::to_string(ccx_run.process.exit_code);
    return false;
  }
  const testing::CcxResult result = testing::ParseDat(dir.path() / "model.dat");
  const auto top = result.totals.find(testing::CcxSetName("top"));
  if (top == result.totals.end()) {
    *error = "no TOP reaction in model.dat";
    return false;
  }
  run->seconds = ccx_run.wall_seconds;
  run->top_force_n = top->second[2];
  return true;
}

// Arguments: cells per edge; the element, an index into kElements.
constexpr ElementType kElements[] = {ElementType::kHex8Full, ElementType::kHex8};

void BM_PeerPressedCube(benchmark::State& state) {
  const int cells = static_cast<int>(state.range(0));
  const ElementType element = kElements[state.range(1)];
  const SceneSpec scene = PressedCube(cells, element);
  Solution solution;
  double pba_seconds = 0;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    const Status status = SolveScene(scene, SolveOptions(), &solution);
    pba_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!status.ok()) {
      state.SkipWithError(status.ToString().c_str());
      return;
    }
  }
  const Summary& s = solution.summary;
  const double ours = s.reactions.at(0).force_n[2];
  state.counters["dofs"] = static_cast<double>(s.dofs);
  state.counters["increments"] = static_cast<double>(s.increments.size());
  state.counters["iterations"] = s.newton_iterations;
  state.counters["pba_s"] = pba_seconds;
  state.counters["assembly_s"] = s.newton_assembly_s;
  state.counters["solve_s"] = s.newton_linear_solve_s;
  state.counters["reaction_mN"] = 1e3 * ours;

  // ccx runs once per mesh, on the C3D8 model; a HEX8 row filtered to run
  // alone runs it itself.
  auto peer = PeerRuns().find(cells);
  if (peer == PeerRuns().end()) {
    PeerRun run;
    std::string error;
    if (!RunPeer(scene, &run, &error)) {
      state.SkipWithError(error.c_str());
      return;
    }
    peer = PeerRuns().emplace(cells, run).first;
  }
  const double difference =
      std::abs(ours - peer->second.top_force_n) / std::abs(peer->second.top_force_n);
  state.counters["ccx_s"] = peer->second.seconds;
  state.counters["ccx_over_pba"] = peer->second.seconds / pba_seconds;
  state.counters["ccx_reaction_mN"] = 1e3 * peer->second.top_force_n;
  state.counters["reaction_rel_diff"] = difference;
  const std::string verdict = element != ElementType::kHex8Full ? "mean dilatation: its own answer"
                              : difference <= kAgreement        ? "same model: agrees"
                                                         : "same model: DISAGREES beyond 1e-5";
  state.SetLabel(verdict + "; " + s.linear_solver);
}

BENCHMARK(BM_PeerPressedCube)
    ->ArgNames({"cells", "element"})
    ->ArgsProduct({{16, 24}, {0, 1}})
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->Iterations(1);

}  // namespace
}  // namespace pba

BENCHMARK_MAIN();
