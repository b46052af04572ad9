// Checkpoints and restarts of QUASI_STATIC (SolveOptions::checkpoint_dir,
// restart_from): a viscoelastic cube pressed by a rigid plane with friction
// and held, interrupted part way and resumed from its checkpoint, must end
// where the uninterrupted run ends - displacement, history rows, reactions
// and contact forces - since the checkpoint carries the viscous history,
// the contact's multipliers and stick points and Newton's step size. A
// checkpoint of another model, or a file that is not one, is refused.
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "analysis/checkpoint.h"
#include "common/scene_builders.h"
#include "pba/solve.h"

namespace pba {
namespace {

namespace fs = std::filesystem;
using K = BoundaryConditionSpec::Kind;
using testing::Condition;

// A 10 mm cube on symmetry planes, its top pressed 1 mm by a rigid plane in
// 1 s and held until `end_s`; brain tissue with two relaxation times.
SceneSpec PressAndHold(double end_s = 20) {
  SceneSpec s;
  s.name = "pressed cube";
  s.geometry.kind = GeometrySpec::Kind::kBox;
  s.geometry.box.size_mm = {10, 10, 10};
  s.mesh.element = ElementType::kTet4Anp;
  s.mesh.element_size_mm = 5;
  s.material.kind = MaterialSpec::Kind::kOgden;
  s.material.ogden.terms = {{842, -4.7}};
  s.material.ogden.bulk_modulus_pa = 842e3;
  s.material.viscoelastic.form = ViscoelasticSpec::Form::kProny;
  s.material.viscoelastic.g = {0.45, 0.365};
  s.material.viscoelastic.tau_s = {0.5, 5};
  s.boundary_conditions = {Condition("bottom", K::kDisplacement, {std::nullopt, std::nullopt, 0.0}),
                           Condition("x_min", K::kDisplacement, {0.0, std::nullopt, std::nullopt}),
                           Condition("y_min", K::kDisplacement, {std::nullopt, 0.0, std::nullopt})};
  ContactSpec plane;
  plane.name = "plate";
  plane.set = "top";
  plane.shape = ContactSpec::Shape::kPlane;
  plane.position_mm = {5, 5, 12};
  plane.axis = {0, 0, -1};
  plane.motion_mm = {0, 0, -1};
  plane.friction = 0.2;
  plane.start_touching = true;
  s.contacts = {plane};
  s.analysis.type = AnalysisSpec::Type::kQuasiStatic;
  s.analysis.time.end_time_s = end_s;
  s.analysis.time.initial_step_s = 0.1;
  s.analysis.time.max_step_s = 2;
  s.analysis.time.curve = {{0, 0}, {1, 1}, {end_s, 1}};
  s.outputs.reaction_sets = {"bottom"};
  return s;
}

fs::path TempDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() /
                       ("pba_checkpoint_test_" + std::to_string(::getpid()) + "_" + name);
  fs::remove_all(dir);
  return dir;
}

double RelativeDifference(const std::vector<double>& a, const std::vector<double>& b) {
  EXPECT_EQ(a.size(), b.size());
  double scale = 0, diff = 0;
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) {
    scale = std::max(scale, std::abs(a[i]));
    diff = std::max(diff, std::abs(a[i] - b[i]));
  }
  return diff / std::max(scale, 1e-300);
}

class CheckpointRestartTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    full_dir_ = new fs::path(TempDir("full"));
    full_ = new Solution();
    SolveOptions options;
    options.checkpoint_dir = *full_dir_;
    options.checkpoint_every_s = 0;  // every step
    const Status status = SolveScene(PressAndHold(), options, full_);
    ASSERT_TRUE(status.ok()) << status.ToString();
  }
  static void TearDownTestSuite() {
    fs::remove_all(*full_dir_);
    delete full_dir_;
    delete full_;
  }
  static fs::path* full_dir_;
  static Solution* full_;
};
fs::path* CheckpointRestartTest::full_dir_ = nullptr;
Solution* CheckpointRestartTest::full_ = nullptr;

TEST_F(CheckpointRestartTest, TheLastStepLeavesACheckpointAtTheEnd) {
  Checkpoint c;
  const Status status = ReadCheckpoint(*full_dir_ / "checkpoint.h5", &c);
  ASSERT_TRUE(status.ok()) << status.ToString();
  EXPECT_EQ(c.time_s, 20);
  EXPECT_EQ(c.load_factor, 1);
  EXPECT_EQ(c.scene_name, "pressed cube");
  EXPECT_EQ(c.solver_version, SolverVersion());
  EXPECT_EQ(c.history.size(), full_->history.size());
  EXPECT_EQ(c.report.increments.size(), full_->summary.time_steps.size());
  EXPECT_EQ(c.step_time_s, full_->step_time_s);
  ASSERT_EQ(c.contact_states.size(), 1u);
  EXPECT_FALSE(c.material_history.empty());
  // The plate pressed: its force is in the history and the summary.
  ASSERT_EQ(full_->summary.contacts.size(), 1u);
  EXPECT_GT(full_->summary.contacts[0].peak_force_n, 0);
  // No temporary file is left beside it.
  int files = 0;
  for (const auto& entry : fs::directory_iterator(*full_dir_)) {
    ++files;
    EXPECT_EQ(entry.path().filename(), "checkpoint.h5");
  }
  EXPECT_EQ(files, 1);
}

TEST_F(CheckpointRestartTest, AnInterruptedRunResumedEndsWhereTheUninterruptedOneDoes) {
  const fs::path dir = TempDir("interrupted");
  std::atomic<bool> cancel{false};
  SolveOptions options;
  options.checkpoint_dir = dir;
  options.checkpoint_every_s = 0;
  options.cancel = &cancel;
  // Stop once the solve is past 40 % of its time (newton covers 0.05-0.85).
  options.progress = [&](const ProgressEvent& e) {
    if (e.phase == "newton" && e.fraction >= 0.05 + 0.8 * 0.4) cancel = true;
  };
  Solution interrupted;
  const Status stopped = SolveScene(PressAndHold(), options, &interrupted);
  ASSERT_EQ(stopped.code(), Status::Code::kCancelled) << stopped.ToString();
  Checkpoint c;
  ASSERT_TRUE(ReadCheckpoint(dir / "checkpoint.h5", &c).ok());
  std::printf("interrupted at t = %g s after %zu steps\n", c.time_s, c.report.increments.size());
  EXPECT_GT(c.time_s, 0);
  EXPECT_LT(c.time_s, 20);

  SolveOptions again;
  again.restart_from = dir / "checkpoint.h5";
  Solution resumed;
  const Status status = SolveScene(PressAndHold(), again, &resumed);
  ASSERT_TRUE(status.ok()) << status.ToString();

  EXPECT_LE(RelativeDifference(resumed.displacement_mm, full_->displacement_mm), 1e-10);
  EXPECT_LE(RelativeDifference(resumed.stress_pa, full_->stress_pa), 1e-10);
  EXPECT_LE(RelativeDifference(resumed.step_displacement_mm, full_->step_displacement_mm), 1e-10);
  EXPECT_EQ(resumed.step_time_s, full_->step_time_s);
  EXPECT_EQ(resumed.history_columns, full_->history_columns);
  ASSERT_EQ(resumed.history.size(), full_->history.size());
  for (std::size_t i = 0; i < resumed.history.size(); ++i) {
    EXPECT_LE(RelativeDifference(resumed.history[i], full_->history[i]), 1e-10) << "row " << i;
  }
  ASSERT_EQ(resumed.summary.reactions.size(), full_->summary.reactions.size());
  for (std::size_t i = 0; i < resumed.summary.reactions.size(); ++i) {
    const auto& a = resumed.summary.reactions[i].force_n;
    const auto& b = full_->summary.reactions[i].force_n;
    EXPECT_LE(RelativeDifference({a.begin(), a.end()}, {b.begin(), b.end()}), 1e-10);
  }
  ASSERT_EQ(resumed.summary.contacts.size(), 1u);
  const auto& fa = resumed.summary.contacts[0].force_n;
  const auto& fb = full_->summary.contacts[0].force_n;
  EXPECT_LE(RelativeDifference({fa.begin(), fa.end()}, {fb.begin(), fb.end()}), 1e-10);
  EXPECT_EQ(resumed.summary.contacts[0].peak_force_n, full_->summary.contacts[0].peak_force_n);
  EXPECT_EQ(resumed.summary.time_steps.size(), full_->summary.time_steps.size());
  EXPECT_EQ(resumed.summary.newton_iterations, full_->summary.newton_iterations);
  fs::remove_all(dir);
}

TEST_F(CheckpointRestartTest, ARunMayBeExtendedPastItsCheckpoint) {
  SolveOptions options;
  options.restart_from = *full_dir_ / "checkpoint.h5";
  Solution extended;
  const Status status = SolveScene(PressAndHold(40), options, &extended);
  ASSERT_TRUE(status.ok()) << status.ToString();
  ASSERT_GT(extended.history.size(), full_->history.size());
  EXPECT_NEAR(extended.history.back()[0], 40, 1e-9);
  for (std::size_t i = 0; i < full_->history.size(); ++i) {
    EXPECT_EQ(extended.history[i], full_->history[i]) << "row " << i;
  }
  // Still relaxing: the plate's force falls through the extension.
  const auto& columns = extended.history_columns;
  const auto z = std::find(columns.begin(), columns.end(), "contact plate z [N]");
  ASSERT_NE(z, columns.end());
  const std::size_t k = static_cast<std::size_t>(z - columns.begin());
  EXPECT_LT(std::abs(extended.history.back()[k]), std::abs(full_->history.back()[k]) * (1 - 1e-6));
}

TEST_F(CheckpointRestartTest, ACheckpointOfAnotherModelIsRefusedNamingWhatDiffers) {
  SolveOptions options;
  options.restart_from = *full_dir_ / "checkpoint.h5";
  struct Case {
    std::string what;
    SceneSpec scene;
  };
  SceneSpec finer = PressAndHold();
  finer.mesh.element_size_mm = 2.5;
  SceneSpec stiffer = PressAndHold();
  stiffer.material.ogden.terms[0].mu_pa = 1000;
  SceneSpec held = PressAndHold();
  held.boundary_conditions[0].displacement_mm = {0.0, 0.0, 0.0};
  SceneSpec rough = PressAndHold();
  rough.contacts[0].friction = 0.3;
  SceneSpec shorter = PressAndHold(10);
  for (const Case& c : {Case{"mesh has", finer}, Case{"materials differ", stiffer},
                        Case{"boundary conditions differ", held}, Case{"contacts differ", rough},
                        Case{"past this analysis' end", shorter},
                        Case{"nothing is left to solve", PressAndHold()}}) {
    Solution solution;
    const Status status = SolveScene(c.scene, options, &solution);
    std::printf("%s\n", status.ToString().c_str());
    EXPECT_EQ(status.code(), Status::Code::kFailedPrecondition) << status.ToString();
    EXPECT_NE(status.message().find(c.what), std::string::npos) << status.ToString();
  }
}

TEST_F(CheckpointRestartTest, AFileThatIsNotACheckpointIsRefused) {
  const fs::path dir = TempDir("corrupt");
  fs::create_directories(dir);
  std::ofstream(dir / "checkpoint.h5") << "not HDF5";
  SolveOptions options;
  options.restart_from = dir / "checkpoint.h5";
  Solution solution;
  Status status = SolveScene(PressAndHold(), options, &solution);
  EXPECT_EQ(status.code(), Status::Code::kInvalidArgument) << status.ToString();
  EXPECT_NE(status.message().find("not a readable checkpoint"), std::string::npos)
      << status.ToString();
  options.restart_from = dir / "missing.h5";
  status = SolveScene(PressAndHold(), options, &solution);
  EXPECT_EQ(status.code(), Status::Code::kInvalidArgument) << status.ToString();
  // A truncated checkpoint.
  const fs::path truncated = dir / "truncated.h5";
  fs::copy_file(*full_dir_ / "checkpoint.h5", truncated);
  fs::resize_file(truncated, fs::file_size(truncated) / 2);
  options.restart_from = truncated;
  status = SolveScene(PressAndHold(), options, &solution);
  EXPECT_EQ(status.code(), Status::Code::kInvalidArgument) << status.ToString();
  fs::remove_all(dir);
}

TEST_F(CheckpointRestartTest, OnlyQuasiStaticRestarts) {
  for (auto type : {AnalysisSpec::Type::kNonlinearStatic, AnalysisSpec::Type::kLinearStatic}) {
    SceneSpec s = PressAndHold();
    s.analysis.type = type;
    s.material.viscoelastic = ViscoelasticSpec();
    s.analysis.time = TimeSpec();
    s.contacts.clear();
    s.mesh.element = ElementType::kTet4;
    SolveOptions options;
    options.restart_from = *full_dir_ / "checkpoint.h5";
    Solution solution;
    const Status status = SolveScene(s, options, &solution);
    EXPECT_EQ(status.code(), Status::Code::kInvalidArgument) << status.ToString();
    EXPECT_EQ(status.field(), "restart_from") << status.ToString();
  }
}

}  // namespace
}  // namespace pba
