#include "jobs/job_executor.h"

#include <google/protobuf/util/time_util.h>
#include <gtest/gtest.h>

#include <fstream>
#include <thread>

#include "unit/server/server_test_support.h"

namespace pba {
namespace {

using testing::TempDir;
using testing::ValidScene;
using testing::WaitUntil;

namespace fs = std::filesystem;

// sha256("hello\n")
constexpr char kHelloSha256[] = "5891b5b522d5df086d0ff0b110fbd9d21bb4fc7163af34d08286a2e846f6be03";

class JobExecutorTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(JobStore::Open(dir_.path() / "pba.db", &store_).ok());
    options_.data_dir = dir_.path();
    options_.solver = testing::WriteFakeSolver(dir_.path());
    options_.kill_grace = std::chrono::milliseconds(500);
    options_.idle_poll = std::chrono::milliseconds(100);
  }

  void StartExecutor() {
    executor_ = std::make_unique<JobExecutor>(*store_, hub_, options_);
    executor_->Start();
  }

  std::string Submit(const std::string& scene_name) {
    v1::Job job;
    bool created = false;
    EXPECT_TRUE(store_->CreateJob(ValidScene(scene_name), "", "alice", &job, &created).ok());
    if (executor_) executor_->Wake();
    return job.id();
  }

  v1::Job Get(const std::string& id) {
    v1::Job job;
    bool found = false;
    EXPECT_TRUE(store_->GetJob(id, JobView::kFull, &job, &found).ok());
    return job;
  }

  v1::Job WaitForState(const std::string& id, v1::Job::State state) {
    EXPECT_TRUE(WaitUntil([&] { return Get(id).state() == state; }))
        << "job " << id << " is " << v1::Job::State_Name(Get(id).state()) << ", not "
        << v1::Job::State_Name(state) << "; error: " << Get(id).error();
    return Get(id);
  }

  v1::Job RunToEnd(const std::string& scene_name) {
    if (!executor_) StartExecutor();
    const std::string id = Submit(scene_name);
    EXPECT_TRUE(WaitUntil([&] {
      const v1::Job::State state = Get(id).state();
      return state != v1::Job::QUEUED && state != v1::Job::RUNNING;
    }));
    return Get(id);
  }

  std::vector<v1::JobEvent> Events(const std::string& id) {
    std::vector<v1::JobEvent> events;
    EXPECT_TRUE(store_->ListEvents(id, 0, &events).ok());
    return events;
  }

  TempDir dir_;
  std::unique_ptr<JobStore> store_;
  JobEventHub hub_;
  ExecutorOptions options_;
  std::unique_ptr<JobExecutor> executor_;
};

TEST_F(JobExecutorTest, SuccessRecordsSummaryFilesAndEvents) {
  const v1::Job job = RunToEnd("ok");
  ASSERT_EQ(job.state(), v1::Job::SUCCEEDED) << job.error();
  EXPECT_EQ(job.attempts(), 1);
  EXPECT_EQ(job.summary().scene_name(), "ok");
  EXPECT_EQ(job.summary().modelled().nodes(), 27);
  EXPECT_DOUBLE_EQ(job.progress(), 1.0);
  EXPECT_TRUE(job.error().empty());
  ASSERT_EQ(job.result_files_size(), 4);
  EXPECT_EQ(job.result_files(0).name(), "SHA256SUMS");  // the list pba-solve wrote last
  EXPECT_EQ(job.result_files(1).name(), "result.h5");
  EXPECT_EQ(job.result_files(1).size_bytes(), 6);
  EXPECT_EQ(job.result_files(1).sha256(), kHelloSha256);
  EXPECT_EQ(job.result_files(2).name(), "result.xdmf");
  EXPECT_EQ(job.result_files(3).name(), "summary.json");

  const fs::path job_dir = dir_.path() / "jobs" / job.id();
  EXPECT_TRUE(fs::exists(job_dir / "scene.json"));
  EXPECT_TRUE(fs::exists(job_dir / "result" / "result.h5"));
  std::ifstream log(job_dir / "solve.log");
  std::string log_text((std::istreambuf_iterator<char>(log)), std::istreambuf_iterator<char>());
  EXPECT_NE(log_text.find("fake pba-solve: scene ok"), std::string::npos) << log_text;

  const std::vector<v1::JobEvent> events = Events(job.id());
  ASSERT_GE(events.size(), 5u);
  EXPECT_EQ(events.front().state(), v1::Job::QUEUED);
  EXPECT_EQ(events[1].state(), v1::Job::RUNNING);
  EXPECT_EQ(events.back().state(), v1::Job::SUCCEEDED);
  // Numbered in the order they happened: the progress events the executor
  // stamps and the state changes the store stamps share one clock.
  using google::protobuf::util::TimeUtil;
  for (size_t i = 1; i < events.size(); ++i) {
    EXPECT_GT(events[i].sequence(), events[i - 1].sequence());
    EXPECT_GE(TimeUtil::TimestampToMicroseconds(events[i].time()),
              TimeUtil::TimestampToMicroseconds(events[i - 1].time()))
        << "event " << events[i].sequence() << " is older than the one before it";
  }
  // Each phase change is stored: mesh, solve, write.
  std::vector<std::string> phases;
  for (const v1::JobEvent& event : events) {
    if (event.state() == v1::Job::RUNNING && !event.phase().empty())
      phases.push_back(event.phase());
  }
  EXPECT_EQ(phases, (std::vector<std::string>{"mesh", "solve", "write"}));
}

// A result is taken only as pba-solve listed it in SHA256SUMS: a file cut
// short, lost or added after it was listed, or the list itself missing,
// fails the job naming the file, and no file of it is offered.
TEST_F(JobExecutorTest, AResultNotAsPbaSolveListedItFailsTheJobNamingTheFile) {
  const std::pair<const char*, const char*> cases[] = {
      {"damaged", "result.h5 is damaged: its SHA-256 is"},
      {"lost", "lacks result.xdmf, which SHA256SUMS names"},
      {"stray", "holds stray.txt, which SHA256SUMS does not name"},
      {"unlisted", "has no SHA256SUMS"},
  };
  for (const auto& [name, words] : cases) {
    const v1::Job job = RunToEnd(name);
    EXPECT_EQ(job.state(), v1::Job::FAILED) << name;
    EXPECT_NE(job.error().find("pba-solve succeeded but"), std::string::npos) << job.error();
    EXPECT_NE(job.error().find(words), std::string::npos) << job.error();
    EXPECT_EQ(job.result_files_size(), 0) << name;
    EXPECT_FALSE(job.has_summary()) << name;
  }
}

// Every solve is told where the shared atlas mesh cache is, and its bound.
TEST_F(JobExecutorTest, SolvesShareTheAtlasCache) {
  options_.atlas_cache_dir = dir_.path() / "cache" / "atlas";
  options_.atlas_cache_gib = 0.5;
  const v1::Job job = RunToEnd("ok");
  ASSERT_EQ(job.state(), v1::Job::SUCCEEDED) << job.error();
  std::ifstream log(dir_.path() / "jobs" / job.id() / "solve.log");
  std::string log_text((std::istreambuf_iterator<char>(log)), std::istreambuf_iterator<char>());
  EXPECT_NE(log_text.find(" --atlas-cache " + options_.atlas_cache_dir.string() +
                          " --atlas-cache-size 0.5"),
            std::string::npos)
      << log_text;
}

TEST_F(JobExecutorTest, ProgressIsStoredThrottled) {
  const v1::Job job = RunToEnd("throttle");
  ASSERT_EQ(job.state(), v1::Job::SUCCEEDED) << job.error();
  std::vector<double> stored;
  for (const v1::JobEvent& event : Events(job.id())) {
    if (event.phase() == "solve" && event.state() == v1::Job::RUNNING) {
      stored.push_back(event.progress());
    }
  }
  // 0.11 and 0.12 are live only: less than 5 % above the last stored 0.10.
  EXPECT_EQ(stored, (std::vector<double>{0.10, 0.20}));
  // Live events used sequence numbers: the stored history has gaps.
  const std::vector<v1::JobEvent> events = Events(job.id());
  EXPECT_GT(events.back().sequence(), static_cast<int64_t>(events.size()));
}

TEST_F(JobExecutorTest, ErrorLineBecomesTheFailure) {
  const v1::Job job = RunToEnd("error");
  EXPECT_EQ(job.state(), v1::Job::FAILED);
  EXPECT_EQ(job.error(), "material.linear_elastic: stiffness matrix is singular");
  EXPECT_EQ(job.phase(), "assemble");
  EXPECT_EQ(job.result_files_size(), 0);
  EXPECT_EQ(Events(job.id()).back().message(), job.error());
}

TEST_F(JobExecutorTest, ExitCodeWithoutErrorLine) {
  const v1::Job job = RunToEnd("exit13");
  EXPECT_EQ(job.state(), v1::Job::FAILED);
  EXPECT_EQ(job.error(), "pba-solve exited with code 13 (reading or writing a file failed)");
}

TEST_F(JobExecutorTest, KilledFromOutside) {
  const v1::Job job = RunToEnd("killed");
  EXPECT_EQ(job.state(), v1::Job::FAILED);
  EXPECT_EQ(job.error(), "pba-solve was killed by signal 9 (SIGKILL)");
  // The executor keeps working.
  EXPECT_EQ(RunToEnd("ok").state(), v1::Job::SUCCEEDED);
}

TEST_F(JobExecutorTest, MissingSolverFailsTheJob) {
  options_.solver = dir_.path() / "no-such-solver";
  const v1::Job job = RunToEnd("ok");
  EXPECT_EQ(job.state(), v1::Job::FAILED);
  EXPECT_NE(job.error().find("no-such-solver"), std::string::npos) << job.error();
}

TEST_F(JobExecutorTest, CancelQueuedJobAtOnce) {
  // No executor running: the job stays queued.
  executor_ = std::make_unique<JobExecutor>(*store_, hub_, options_);
  const std::string id = Submit("ok");
  v1::Job job;
  bool found = false;
  ASSERT_TRUE(executor_->Cancel(id, &job, &found).ok());
  EXPECT_TRUE(found);
  EXPECT_EQ(job.state(), v1::Job::CANCELLED);
  EXPECT_EQ(job.error(), "cancelled before it started");
  // Cancelling again changes nothing.
  ASSERT_TRUE(executor_->Cancel(id, &job, &found).ok());
  EXPECT_EQ(job.state(), v1::Job::CANCELLED);
  EXPECT_EQ(Events(id).size(), 2u);
  ASSERT_TRUE(executor_->Cancel("j0000000000", &job, &found).ok());
  EXPECT_FALSE(found);
}

TEST_F(JobExecutorTest, CancelRunningJob) {
  StartExecutor();
  const std::string id = Submit("slow");
  ASSERT_TRUE(WaitUntil([&] { return Get(id).phase() == "mesh"; }));
  v1::Job job;
  bool found = false;
  ASSERT_TRUE(executor_->Cancel(id, &job, &found).ok());
  // The answer is the job as the request left it: still RUNNING while the
  // solver stops, or already CANCELLED when it stopped at once.
  EXPECT_TRUE(job.state() == v1::Job::RUNNING || job.state() == v1::Job::CANCELLED)
      << v1::Job::State_Name(job.state());
  job = WaitForState(id, v1::Job::CANCELLED);
  EXPECT_EQ(job.error(), "cancelled by request");
  EXPECT_FALSE(fs::exists(dir_.path() / "jobs" / id / "result"));
}

TEST_F(JobExecutorTest, CancelEscalatesToSigkill) {
  StartExecutor();
  const std::string id = Submit("stubborn");
  ASSERT_TRUE(WaitUntil([&] { return Get(id).phase() == "mesh"; }));
  const auto start = std::chrono::steady_clock::now();
  v1::Job job;
  bool found = false;
  ASSERT_TRUE(executor_->Cancel(id, &job, &found).ok());
  WaitForState(id, v1::Job::CANCELLED);
  EXPECT_GE(std::chrono::steady_clock::now() - start, options_.kill_grace);
}

// A solve cancelled while it writes its result ends without removing its
// staging directory (the watchdog of pba-solve exits at once); the job's
// folder keeps none of it.
TEST_F(JobExecutorTest, ACancelWhileWritingLeavesNoStagingDirectory) {
  StartExecutor();
  const std::string id = Submit("partial");
  const fs::path job_dir = dir_.path() / "jobs" / id;
  ASSERT_TRUE(WaitUntil([&] { return Get(id).phase() == "write"; }));
  const auto staged = [&] {
    int found = 0;
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(job_dir, ec)) {
      found += entry.path().filename().string().rfind(".result.", 0) == 0;
    }
    return found;
  };
  ASSERT_EQ(staged(), 1);
  v1::Job job;
  bool found = false;
  ASSERT_TRUE(executor_->Cancel(id, &job, &found).ok());
  job = WaitForState(id, v1::Job::CANCELLED);
  EXPECT_EQ(job.error(), "cancelled by request");
  EXPECT_EQ(staged(), 0) << "a half-written result stays in " << job_dir;
  EXPECT_FALSE(fs::exists(job_dir / "result"));
  EXPECT_TRUE(fs::exists(job_dir / "solve.log"));
}

TEST_F(JobExecutorTest, StopRequeuesRunningJobs) {
  StartExecutor();
  const std::string id = Submit("slow");
  ASSERT_TRUE(WaitUntil([&] { return Get(id).phase() == "mesh"; }));
  executor_->Stop();
  const v1::Job job = Get(id);
  EXPECT_EQ(job.state(), v1::Job::QUEUED);
  EXPECT_EQ(job.attempts(), 1);
  EXPECT_EQ(Events(id).back().message(), "re-queued: server shut down");
  EXPECT_EQ(Events(id).back().state(), v1::Job::QUEUED);
}

TEST_F(JobExecutorTest, RunsJobsConcurrentlyUpToMaxRunning) {
  options_.max_running = 2;
  StartExecutor();
  const std::string a = Submit("slow");
  const std::string b = Submit("slow");
  const std::string c = Submit("slow");
  ASSERT_TRUE(WaitUntil(
      [&] { return Get(a).state() == v1::Job::RUNNING && Get(b).state() == v1::Job::RUNNING; }));
  EXPECT_EQ(Get(c).state(), v1::Job::QUEUED);
  v1::Job job;
  bool found = false;
  ASSERT_TRUE(executor_->Cancel(a, &job, &found).ok());
  WaitForState(c, v1::Job::RUNNING);
}

TEST_F(JobExecutorTest, RemovesLeftoversOfAnEarlierAttempt) {
  const std::string id = Submit("ok");
  const fs::path job_dir = dir_.path() / "jobs" / id;
  fs::create_directories(job_dir / ".result.partial-12345");
  fs::create_directories(job_dir / "result");
  std::ofstream(job_dir / "result" / "stale.txt") << "old";
  StartExecutor();
  const v1::Job job = WaitForState(id, v1::Job::SUCCEEDED);
  EXPECT_FALSE(fs::exists(job_dir / ".result.partial-12345"));
  EXPECT_FALSE(fs::exists(job_dir / "result" / "stale.txt"));
  EXPECT_EQ(job.result_files_size(), 4);  // with SHA256SUMS
}

TEST_F(JobExecutorTest, PublishesLiveEventsToTheHub) {
  StartExecutor();
  const std::string id = Submit("slow");
  ASSERT_TRUE(WaitUntil([&] {
    std::string phase;
    double progress = 0;
    return hub_.Live(id, &phase, &progress) && phase == "mesh";
  }));
  const std::vector<v1::JobEvent> recent = hub_.Recent(id, 0);
  ASSERT_FALSE(recent.empty());
  EXPECT_EQ(recent.back().phase(), "mesh");
  v1::Job job;
  bool found = false;
  ASSERT_TRUE(executor_->Cancel(id, &job, &found).ok());
  WaitForState(id, v1::Job::CANCELLED);
  std::string phase;
  double progress = 0;
  EXPECT_FALSE(hub_.Live(id, &phase, &progress));
}

TEST_F(JobExecutorTest, ATimeLimitStopsTheJob) {
  StartExecutor();
  NewJob request;
  request.owner = "alice";
  request.scene = ValidScene("slow");
  request.timeout_s = 1;
  v1::Job job;
  bool created = false;
  ASSERT_TRUE(store_->CreateJob(request, &job, &created).ok());
  executor_->Wake();
  const v1::Job ended = WaitForState(job.id(), v1::Job::FAILED);
  EXPECT_EQ(ended.error(), "stopped after its time limit of 1 s");
  EXPECT_FALSE(fs::exists(dir_.path() / "jobs" / job.id() / "result"));
}

TEST_F(JobExecutorTest, TheServersTimeLimitBoundsTheJobs) {
  options_.max_job_time = std::chrono::seconds(1);
  const v1::Job job = RunToEnd("slow");
  EXPECT_EQ(job.state(), v1::Job::FAILED);
  EXPECT_EQ(job.error(), "stopped after its time limit of 1 s");
}

TEST_F(JobExecutorTest, GivesUpAJobStartedTooOften) {
  options_.max_attempts = 1;
  const std::string id = Submit("ok");
  // One start that a server stop interrupted.
  v1::Job claimed;
  v1::JobEvent event;
  bool ok = false;
  ASSERT_TRUE(store_->ClaimNextQueued(&claimed, &event, &ok).ok());
  std::vector<v1::JobEvent> requeued;
  ASSERT_TRUE(store_->RequeueInterrupted("re-queued", &requeued).ok());
  StartExecutor();
  const v1::Job job = WaitForState(id, v1::Job::FAILED);
  EXPECT_EQ(job.attempts(), 2);
  EXPECT_NE(job.error().find("started 1 times without finishing"), std::string::npos)
      << job.error();
}

// Stages a marker beside the scene and renames the scene; completes by
// naming a snapshot. Fails either step on request.
class FakePreparation : public JobPreparation {
 public:
  Status Stage(const v1::Job& job, const fs::path& dir, v1::Scene* scene,
               std::vector<std::string>* input) override {
    if (fail_stage) return Status::FailedPrecondition("the snapshot has no structures");
    std::ofstream(dir / "staged.txt") << job.id();
    staged_scene_name = scene->name();
    return Status::Ok();
  }
  Status Complete(const v1::Job& job, const fs::path& result_dir, RunOutcome* outcome) override {
    if (fail_complete) return Status::FailedPrecondition("'putamen' exists already");
    completed_with_summary = fs::exists(result_dir / "summary.json");
    outcome->snapshot.set_project("atlas");
    outcome->snapshot.set_snapshot("12");
    return Status::Ok();
  }
  bool fail_stage = false, fail_complete = false, completed_with_summary = false;
  std::string staged_scene_name;
};

TEST_F(JobExecutorTest, APreparationStagesAndCompletesTheJob) {
  FakePreparation preparation;
  options_.preparation = &preparation;
  const v1::Job job = RunToEnd("ok");
  ASSERT_EQ(job.state(), v1::Job::SUCCEEDED) << job.error();
  EXPECT_EQ(preparation.staged_scene_name, "ok");
  EXPECT_TRUE(preparation.completed_with_summary);
  EXPECT_EQ(job.snapshot().snapshot(), "12");
  EXPECT_TRUE(fs::exists(dir_.path() / "jobs" / job.id() / "staged.txt"));
}

TEST_F(JobExecutorTest, APreparationsRefusalFailsTheJob) {
  FakePreparation preparation;
  options_.preparation = &preparation;
  preparation.fail_stage = true;
  v1::Job job = RunToEnd("ok");
  EXPECT_EQ(job.state(), v1::Job::FAILED);
  EXPECT_EQ(job.error(), "the snapshot has no structures");
  preparation.fail_stage = false;
  preparation.fail_complete = true;
  job = RunToEnd("ok");
  EXPECT_EQ(job.state(), v1::Job::FAILED);
  EXPECT_EQ(job.error(), "'putamen' exists already");
  EXPECT_EQ(job.result_files_size(), 0);
}

TEST_F(JobExecutorTest, RemovesTheFilesOfOldJobsAtStart) {
  const v1::Job job = RunToEnd("ok");
  ASSERT_EQ(job.state(), v1::Job::SUCCEEDED);
  executor_->Stop();
  executor_.reset();
  const fs::path folder = dir_.path() / "jobs" / job.id();
  ASSERT_TRUE(fs::exists(folder / "result" / "result.h5"));
  std::this_thread::sleep_for(std::chrono::milliseconds(1100));
  options_.keep_results = std::chrono::seconds(1);
  StartExecutor();
  ASSERT_TRUE(WaitUntil([&] { return !fs::exists(folder); }));
  const v1::Job expired = Get(job.id());
  EXPECT_EQ(expired.state(), v1::Job::SUCCEEDED);
  EXPECT_EQ(expired.result_files_size(), 0);
  EXPECT_NE(expired.error().find("removed"), std::string::npos) << expired.error();
}

}  // namespace
}  // namespace pba
