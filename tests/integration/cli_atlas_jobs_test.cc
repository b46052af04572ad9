// End to end through the real pba-server (with the real pba-solve) and the
// real pba client: an atlas imported into a project as a job, a scene run
// against the snapshot the import made, the project's watchers told of the
// job, the snapshot exported and solved again locally to the same mesh; a
// label volume imported, and a second import of the same structures failing
// without writing anything.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <future>
#include <regex>
#include <sstream>
#include <string>
#include <thread>

#include "common/subprocess.h"

namespace pba::testing {
namespace {
namespace fs = std::filesystem;
using std::chrono::seconds;

constexpr int kJobFailed = 6;

// The first match of `pattern`'s group 1 in `text`, or "".
std::string Find(const std::string& text, const std::string& pattern) {
  std::smatch match;
  return std::regex_search(text, match, std::regex(pattern)) ? match[1].str() : "";
}

class CliAtlasJobsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    data_ = dir_.path() / "data";
    server_ = std::make_unique<ServerProcess>(PBA_SERVER_BIN, data_);
    std::string log;
    ASSERT_TRUE(server_->Start(&log)) << "pba-server did not start:\n" << log;
    token_ = ReadFile(data_ / "admin.token");
    while (!token_.empty() && token_.back() == '\n') token_.pop_back();
    ASSERT_EQ(Pba({"project", "create", "demo"}).exit_code, 0);
  }

  void TearDown() override {
    if (HasFailure()) std::cerr << "server log:\n" << ReadFile(server_->log_path());
  }

  RunResult Pba(std::vector<std::string> args, seconds timeout = seconds(300)) {
    args.insert(args.begin(), {PBA_CLI_BIN, "--server", server_->address()});
    return RunProcess(args, {"PBA_TOKEN=" + token_}, timeout);
  }

  TempDir dir_;
  fs::path data_;
  std::unique_ptr<ServerProcess> server_;
  std::string token_;
};

TEST_F(CliAtlasJobsTest, ImportRunAgainstTheSnapshotExportAndReproduce) {
  const std::string scene = std::string(PBA_EXAMPLES_DIR) + "/basal_ganglia_push.yaml";
  const RunResult imported =
      Pba({"atlas", "import", "-p", "demo", "--synthetic", "--structure", "Putamen", "--structure",
           "Globus pallidus lateralis", "--snapshot-name", "basal ganglia"});
  ASSERT_EQ(imported.exit_code, 0) << imported.out << imported.err;
  EXPECT_NE(imported.out.find("Imported into demo: snapshot 1"), std::string::npos) << imported.out;
  const RunResult listed = Pba({"atlas", "list", "-p", "demo"});
  EXPECT_NE(listed.out.find("Putamen"), std::string::npos) << listed.out;
  EXPECT_NE(listed.out.find("Globus pallidus lateralis"), std::string::npos) << listed.out;

  // A watcher of the project (for the tag below and the job's three
  // states), then a job against the snapshot.
  std::promise<RunResult> watched;
  std::thread watcher([&] {
    watched.set_value(Pba({"atlas", "watch", "-p", "demo", "--count", "4"}, seconds(300)));
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  // A snapshot is named by the name it was given, its id or a tag.
  const RunResult job =
      Pba({"--json", "job", "submit", scene, "--snapshot", "demo/basal ganglia", "--wait"});
  ASSERT_EQ(job.exit_code, 0) << job.out << job.err;
  watcher.join();
  const RunResult watch = watched.get_future().get();
  EXPECT_NE(watch.out.find("job queued"), std::string::npos) << watch.out;
  EXPECT_NE(watch.out.find("job running"), std::string::npos) << watch.out;
  EXPECT_NE(watch.out.find("job succeeded"), std::string::npos) << watch.out;

  // The job names the snapshot it ran against, by id.
  EXPECT_NE(job.out.find(R"("project": "demo")"), std::string::npos) << job.out;
  EXPECT_NE(job.out.find(R"("snapshot": "1")"), std::string::npos) << job.out;
  EXPECT_NE(job.out.find("atlas of snapshot 1 of project demo (2 structures)"), std::string::npos)
      << job.out;
  const std::string elements = Find(job.out, R"re("elements": "([0-9]+)")re");
  ASSERT_FALSE(elements.empty()) << job.out;
  EXPECT_NE(job.out.find("built, cached as"), std::string::npos) << job.out;

  // The same atlas again, by a tag: its mesh from the cache.
  const RunResult tag = Pba({"atlas", "tag", "-p", "demo", "1", "basal"});
  ASSERT_EQ(tag.exit_code, 0) << tag.out << tag.err;
  const RunResult again =
      Pba({"--json", "job", "submit", scene, "--snapshot", "demo/basal", "--wait"});
  ASSERT_EQ(again.exit_code, 0) << again.out << again.err;
  EXPECT_NE(again.out.find("atlas mesh from the cache"), std::string::npos) << again.out;
  EXPECT_EQ(Find(again.out, R"re("elements": "([0-9]+)")re"), elements);

  // Anyone can rebuild it from an export of the snapshot.
  const fs::path exported = dir_.path() / "exported";
  const RunResult exporting = Pba({"atlas", "export", "-p", "demo", "1", "-o", exported.string()});
  ASSERT_EQ(exporting.exit_code, 0) << exporting.out << exporting.err;
  std::string local_scene = ReadFile(scene);
  local_scene = std::regex_replace(local_scene, std::regex("voxel_size_mm: 2"),
                                   "voxel_size_mm: 2\n    source: " + exported.string());
  const fs::path local = dir_.path() / "local.yaml";
  std::ofstream(local) << local_scene;
  const RunResult solved = RunProcess({PBA_SOLVE_BIN, local.string(), "--out",
                                       (dir_.path() / "local").string(), "--progress", "none"},
                                      seconds(300));
  ASSERT_EQ(solved.exit_code, 0) << solved.out << solved.err;
  const std::string summary = ReadFile(dir_.path() / "local" / "summary.json");
  EXPECT_EQ(Find(summary, R"re("elements": "([0-9]+)")re"), elements) << summary;
  EXPECT_NE(summary.find("atlas of snapshot 1 of project demo"), std::string::npos) << summary;
}

TEST_F(CliAtlasJobsTest, ALabelVolumeImportAndARepeatThatFailsWritingNothing) {
  const fs::path plates = dir_.path() / "plates";
  const RunResult written = RunProcess({PBA_ATLAS_BIN, "plates", "-o", plates.string()});
  ASSERT_EQ(written.exit_code, 0) << written.out << written.err;
  const std::string labels = (plates / "labels.nii.gz").string();
  const RunResult imported = Pba({"atlas", "import", "-p", "demo", "--labels", labels,
                                  "--structure", "Putamen", "--structure", "Ventricles"});
  ASSERT_EQ(imported.exit_code, 0) << imported.out << imported.err;
  const RunResult shown = Pba({"atlas", "show", "-p", "demo", "Ventricles"});
  EXPECT_NE(shown.out.find("nifti"), std::string::npos) << shown.out;

  // The same structures again: the job fails naming one, and nothing is written.
  const RunResult repeat =
      Pba({"atlas", "import", "-p", "demo", "--labels", labels, "--structure", "Putamen"});
  EXPECT_EQ(repeat.exit_code, kJobFailed) << repeat.out << repeat.err;
  EXPECT_NE(repeat.err.find("'Putamen'"), std::string::npos) << repeat.err;
  const RunResult snapshots = Pba({"--json", "atlas", "snapshot", "list", "-p", "demo"});
  EXPECT_EQ(Find(snapshots.out, R"re("id": "?([0-9]+))re"), "1") << snapshots.out;
  EXPECT_EQ(snapshots.out.find(R"("id": "2")"), std::string::npos) << snapshots.out;
  const RunResult history = Pba({"atlas", "history", "-p", "demo", "Putamen"});
  EXPECT_EQ(history.exit_code, 0);
  EXPECT_EQ(history.out.find("\n2 "), std::string::npos) << history.out;

  // A label volume import needs its volume.
  const RunResult bad =
      Pba({"atlas", "import", "-p", "demo", "--plates", plates.string(), "--structure", "Putamen"});
  EXPECT_NE(bad.exit_code, 0);
}

}  // namespace
}  // namespace pba::testing
