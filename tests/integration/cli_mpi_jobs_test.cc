// Jobs on several MPI ranks through the real server and client:
// `pba job submit --ranks 2` runs `mpirun -np 2 pba-solve` on the server's
// machine, the job reports its ranks, scenes the ranks cannot share are
// refused at the submit naming the field, and a cancel ends every rank.

#include <signal.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include "integration/block_scene.h"
#include "integration/server_fixture.h"

namespace pba::testing {
namespace {
namespace fs = std::filesystem;
using std::chrono::seconds;

constexpr int kInvalid = 5;
constexpr int kJobCancelled = 7;

class MpiJobsTest : public ServerTest {
 protected:
  void SetUp() override {
    // The server of the fixture, restarted with a stated rank limit (the
    // default, the machine's cores, differs between machines).
    ServerTest::SetUp();
    server_->Stop();
    std::string log;
    ASSERT_TRUE(server_->Start(&log, {"--max-ranks", "2"})) << log;
  }

  // An example with `from` replaced by `to`.
  fs::path Example(const std::string& example, const std::string& from, const std::string& to) {
    std::string text = ReadFile(fs::path(PBA_EXAMPLES_DIR) / (example + ".yaml"));
    const std::size_t at = text.find(from);
    if (at != std::string::npos) text.replace(at, from.size(), to);
    return WriteScene(example + "-variant.yaml", text);
  }
};

TEST_F(MpiJobsTest, AJobOnTwoRanksSucceedsAndSaysSo) {
  const fs::path scene = Example("quickstart", "linear_solver: CHOLMOD", "linear_solver: AUTO");
  const RunResult submitted = Pba({"job", "submit", scene.string(), "--ranks", "2", "--wait"});
  ASSERT_EQ(submitted.exit_code, 0) << submitted.out << submitted.err;
  const std::string id = JobId(submitted);
  const RunResult status = Pba({"job", "status", id});
  EXPECT_NE(status.out.find("MPI ranks"), std::string::npos) << status.out;
  EXPECT_NE(status.out.find("on 2 MPI ranks"), std::string::npos) << status.out;
  const RunResult json = Pba({"--json", "job", "status", id});
  EXPECT_TRUE(std::regex_search(json.out, std::regex("\"ranks\": 2\\b"))) << json.out;
  const fs::path out = dir_.path() / "fetched";
  const RunResult fetch = Pba({"job", "fetch", id, "-o", out.string()});
  ASSERT_EQ(fetch.exit_code, 0) << fetch.err;
  EXPECT_TRUE(fs::exists(out / "result.h5"));
}

TEST_F(MpiJobsTest, ScenesTheRanksCannotShareAreRefusedAtTheSubmit) {
  const std::pair<fs::path, std::string> refused[] = {
      {fs::path(PBA_EXAMPLES_DIR) / "gel_impact.yaml", "analysis.type"},
      {fs::path(PBA_EXAMPLES_DIR) / "quickstart.yaml", "analysis.linear_solver"},
  };
  for (const auto& [scene, field] : refused) {
    const RunResult submitted = Pba({"job", "submit", scene.string(), "--ranks", "2"});
    EXPECT_EQ(submitted.exit_code, kInvalid) << submitted.out << submitted.err;
    EXPECT_NE(submitted.err.find(field), std::string::npos) << submitted.err;
  }
  const fs::path scene = Example("quickstart", "linear_solver: CHOLMOD", "linear_solver: AUTO");
  const RunResult too_many = Pba({"job", "submit", scene.string(), "--ranks", "3"});
  EXPECT_EQ(too_many.exit_code, kInvalid) << too_many.err;
  EXPECT_NE(too_many.err.find("ranks"), std::string::npos) << too_many.err;
  EXPECT_NE(too_many.err.find("--max-ranks"), std::string::npos) << too_many.err;
  EXPECT_EQ(JobCount(), 0u);
}

TEST_F(MpiJobsTest, CancelEndsEveryRank) {
  const fs::path scene = WriteScene(
      "long.yaml", BlockSceneYaml("long-running", 50) + "analysis: {linear_solver: AMG}\n");
  const RunResult submitted = Pba({"job", "submit", scene.string(), "--ranks", "2"});
  ASSERT_EQ(submitted.exit_code, 0) << submitted.err;
  const std::string id = JobId(submitted);
  ASSERT_TRUE(WaitForState(id, "RUNNING", seconds(30)));
  // mpirun is the server's child, the ranks mpirun's.
  std::vector<pid_t> ranks;
  for (int i = 0; i < 200 && ranks.size() < 2; ++i) {
    ranks.clear();
    for (const pid_t launcher : ChildrenNamed(server_->pid(), "mpirun")) {
      for (const pid_t rank : ChildrenNamed(launcher, "pba-solve")) ranks.push_back(rank);
    }
    if (ranks.size() < 2) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ASSERT_EQ(ranks.size(), 2u);
  const RunResult cancel = Pba({"job", "cancel", id});
  EXPECT_EQ(cancel.exit_code, 0) << cancel.err;
  const RunResult watch = Pba({"job", "watch", id}, seconds(60));
  EXPECT_EQ(watch.exit_code, kJobCancelled) << watch.out << watch.err;
  for (const pid_t rank : ranks) {
    bool gone = false;
    for (int i = 0; i < 200 && !gone; ++i) {
      gone = ::kill(rank, 0) != 0 ||
             ReadFile("/proc/" + std::to_string(rank) + "/stat").find(") Z") != std::string::npos;
      if (!gone) std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    EXPECT_TRUE(gone) << "rank process " << rank << " outlived the cancel";
  }
  EXPECT_TRUE(ChildrenNamed(server_->pid(), "mpirun").empty());
}

// A batch on two ranks per member: every member's job runs through mpirun.
TEST_F(MpiJobsTest, BatchMembersRunOnTheRanksAsked) {
  const fs::path scene = Example("quickstart", "linear_solver: CHOLMOD", "linear_solver: AUTO");
  const fs::path batch =
      WriteScene("sweep.yaml", "name: sweep\nscene: " + scene.string() +
                                   "\nparallel: 1\nmembers:\n"
                                   "  - {name: soft, set: {}}\n"
                                   "  - {name: pressed, set: "
                                   "{\"boundary_conditions[1].displacement.z_mm\": "
                                   "-1.0}}\n"
                                   "outputs: [results.max_displacement_mm]\n");
  const RunResult run =
      Pba({"batch", "run", batch.string(), "--ranks", "2", "--no-plot"}, seconds(240));
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  const RunResult list = Pba({"--json", "job", "list", "--all"});
  EXPECT_EQ(CountOf(list.out, "\"ranks\": 2"), 2u) << list.out;
}

// A job queued on two ranks before a restart that lowered --max-ranks is
// not run on more ranks than the server now allows: it fails saying why.
TEST_F(MpiJobsTest, AQueuedJobOverALoweredRankLimitFailsSayingSo) {
  const fs::path blocker = WriteScene("long.yaml", BlockSceneYaml("long-running", 50));
  const RunResult first = Pba({"job", "submit", blocker.string()});
  ASSERT_EQ(first.exit_code, 0) << first.err;
  ASSERT_TRUE(WaitForState(JobId(first), "RUNNING", seconds(30)));
  const fs::path scene = Example("quickstart", "linear_solver: CHOLMOD", "linear_solver: AUTO");
  const RunResult queued = Pba({"job", "submit", scene.string(), "--ranks", "2"});
  ASSERT_EQ(queued.exit_code, 0) << queued.err;
  server_->Stop();
  std::string log;
  ASSERT_TRUE(server_->Start(&log, {"--max-ranks", "1"})) << log;
  EXPECT_EQ(Pba({"job", "cancel", JobId(first)}).exit_code, 0);
  ASSERT_TRUE(WaitForState(JobId(queued), "FAILED", seconds(60)));
  const RunResult status = Pba({"job", "status", JobId(queued)});
  EXPECT_NE(status.out.find("this server allows 1"), std::string::npos) << status.out;
}

}  // namespace
}  // namespace pba::testing
