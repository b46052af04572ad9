// Work in a bounded child: past its memory it ends kOutOfMemory, past its
// time kOutOfTime, on a signal kCrashed; a status and output it returns come
// back intact; its private TMPDIR is gone afterwards, however it ended.
#include "service/bounded_child.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <stdlib.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

namespace pba {
namespace {

namespace fs = std::filesystem;
using std::chrono::milliseconds;

// TMPDIR pointed at a fresh empty directory for the test's life, then
// restored.
class BoundedChildTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const char* old = std::getenv("TMPDIR");
    had_tmpdir_ = old != nullptr;
    if (had_tmpdir_) old_tmpdir_ = old;
    std::string pattern = (fs::path(::testing::TempDir()) / "bounded-child-XXXXXX").string();
    ASSERT_NE(::mkdtemp(pattern.data()), nullptr);
    tmpdir_ = pattern;
    ::setenv("TMPDIR", tmpdir_.c_str(), 1);
  }
  void TearDown() override {
    if (had_tmpdir_) {
      ::setenv("TMPDIR", old_tmpdir_.c_str(), 1);
    } else {
      ::unsetenv("TMPDIR");
    }
    std::error_code ignored;
    fs::remove_all(tmpdir_, ignored);
  }

  bool TmpdirIsEmpty() const { return fs::is_empty(tmpdir_); }

  fs::path tmpdir_;

 private:
  bool had_tmpdir_ = false;
  std::string old_tmpdir_;
};

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

TEST_F(BoundedChildTest, AllocatingPastTheLimitEndsOutOfMemory) {
  ChildLimits limits;
  limits.memory_bytes = int64_t{256} << 20;
  // One allocation of 8 GiB: refused by the address-space limit at once.
  ChildOutcome outcome;
  ASSERT_TRUE(RunInBoundedChild(
                  limits,
                  [](std::string* output) {
                    std::vector<char> huge(size_t{8} << 30);
                    *output = std::to_string(huge.size());
                    return Status::Ok();
                  },
                  &outcome)
                  .ok());
  EXPECT_EQ(outcome.end, ChildOutcome::End::kOutOfMemory);
  EXPECT_TRUE(outcome.output.empty());

  // 64 MiB at a time, each written to: refused after a few.
  ASSERT_TRUE(RunInBoundedChild(
                  limits,
                  [](std::string* output) {
                    std::vector<std::unique_ptr<char[]>> blocks;
                    for (int k = 0; k < 128; ++k) {  // 8 GiB in all
                      blocks.emplace_back(new char[size_t{64} << 20]);
                      std::memset(blocks.back().get(), 1, size_t{64} << 20);
                    }
                    *output = "all allocated";
                    return Status::Ok();
                  },
                  &outcome)
                  .ok());
  EXPECT_EQ(outcome.end, ChildOutcome::End::kOutOfMemory) << outcome.output;

  const Status status = OutcomeStatus(outcome, limits, "upload_id", "the nifti file");
  EXPECT_EQ(status.code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(status.field(), "upload_id");
  EXPECT_EQ(status.message().rfind("the nifti file needs more than 256 MiB to check", 0), 0u)
      << status.ToString();
  EXPECT_TRUE(TmpdirIsEmpty());
}

TEST_F(BoundedChildTest, WorkPastTheTimeLimitIsKilled) {
  ChildLimits limits;
  limits.time = milliseconds(500);
  ChildOutcome outcome;
  const auto start = std::chrono::steady_clock::now();
  ASSERT_TRUE(RunInBoundedChild(
                  limits,
                  [](std::string*) {
                    // Leaves a file behind in its TMPDIR, then overstays.
                    std::ofstream(fs::path(std::getenv("TMPDIR")) / "partial.nii") << "data";
                    std::this_thread::sleep_for(std::chrono::seconds(60));
                    return Status::Ok();
                  },
                  &outcome)
                  .ok());
  const double seconds = SecondsSince(start);
  EXPECT_EQ(outcome.end, ChildOutcome::End::kOutOfTime);
  EXPECT_GE(seconds, 0.45);
  EXPECT_LT(seconds, 5) << "the child was not killed at its limit";
  const Status status = OutcomeStatus(outcome, limits, "upload_id", "the stl file");
  EXPECT_EQ(status.code(), Status::Code::kInvalidArgument);
  EXPECT_NE(status.message().find("the stl file took longer than 0.5 s to check"),
            std::string::npos)
      << status.ToString();
  // The killed child's scratch directory went with it.
  EXPECT_TRUE(TmpdirIsEmpty());
}

TEST_F(BoundedChildTest, ASignalOrAnExitIsACrashNamingIt) {
  ChildOutcome outcome;
  ASSERT_TRUE(RunInBoundedChild(
                  {},
                  [](std::string*) {
                    ::raise(SIGSEGV);
                    return Status::Ok();
                  },
                  &outcome)
                  .ok());
  EXPECT_EQ(outcome.end, ChildOutcome::End::kCrashed);
  EXPECT_EQ(outcome.detail, "SIGSEGV");
  const Status status = OutcomeStatus(outcome, {}, "upload_id", "the vtk file");
  EXPECT_EQ(status.code(), Status::Code::kInvalidArgument);
  EXPECT_NE(status.message().find("ended with SIGSEGV"), std::string::npos) << status.ToString();

  ASSERT_TRUE(RunInBoundedChild(
                  {}, [](std::string*) -> Status { ::_exit(3); }, &outcome)
                  .ok());
  EXPECT_EQ(outcome.end, ChildOutcome::End::kCrashed);
  EXPECT_EQ(outcome.detail, "exit code 3");
  EXPECT_TRUE(TmpdirIsEmpty());
}

TEST_F(BoundedChildTest, TheWorksStatusAndOutputComeBackIntact) {
  // Bytes a line-based or NUL-terminated answer would cut.
  const std::string output =
      std::string("first line\nsecond\0with a nul", 28) + std::string(5000, 'x');
  ChildOutcome outcome;
  ASSERT_TRUE(RunInBoundedChild(
                  {},
                  [&](std::string* out) {
                    *out = output;
                    return Status::InvalidArgument("plates[2].z_mm", "another plate is at 1 mm");
                  },
                  &outcome)
                  .ok());
  EXPECT_EQ(outcome.end, ChildOutcome::End::kDone);
  EXPECT_EQ(outcome.status.code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(outcome.status.field(), "plates[2].z_mm");
  EXPECT_EQ(outcome.status.message(), "another plate is at 1 mm");
  EXPECT_EQ(outcome.output, output);
  // kDone: OutcomeStatus is the work's own status.
  const Status status = OutcomeStatus(outcome, {}, "upload_id", "the file");
  EXPECT_EQ(status.field(), "plates[2].z_mm");

  ASSERT_TRUE(RunInBoundedChild(
                  {},
                  [](std::string* out) {
                    *out = "fine";
                    return Status::Ok();
                  },
                  &outcome)
                  .ok());
  EXPECT_EQ(outcome.end, ChildOutcome::End::kDone);
  EXPECT_TRUE(outcome.status.ok());
  EXPECT_EQ(outcome.output, "fine");
}

TEST_F(BoundedChildTest, TheChildsTmpdirIsPrivateAndRemoved) {
  ChildOutcome outcome;
  ASSERT_TRUE(RunInBoundedChild(
                  {},
                  [](std::string* output) {
                    const char* dir = std::getenv("TMPDIR");
                    if (dir == nullptr) return Status::Internal("no TMPDIR");
                    *output = dir;
                    std::ofstream(fs::path(dir) / "copy.nii") << "left behind?";
                    return fs::exists(fs::path(dir) / "copy.nii") ? Status::Ok()
                                                                  : Status::Io("not written");
                  },
                  &outcome)
                  .ok());
  ASSERT_EQ(outcome.end, ChildOutcome::End::kDone);
  ASSERT_TRUE(outcome.status.ok()) << outcome.status.ToString();
  const fs::path child_tmpdir = outcome.output;
  EXPECT_EQ(child_tmpdir.parent_path(), tmpdir_);  // under the server's TMPDIR, its own
  EXPECT_FALSE(fs::exists(child_tmpdir));
  EXPECT_TRUE(TmpdirIsEmpty());
  EXPECT_EQ(std::getenv("TMPDIR"), tmpdir_.string());  // the parent's is untouched
}

TEST_F(BoundedChildTest, ATmpdirThatIsNotADirectoryIsAnErrorNotAThrow) {
  const fs::path file = tmpdir_ / "not-a-directory";
  std::ofstream(file) << "x";
  ::setenv("TMPDIR", file.c_str(), 1);
  bool ran = false;
  ChildOutcome outcome;
  const Status status = RunInBoundedChild(
      {},
      [&](std::string*) {
        ran = true;
        return Status::Ok();
      },
      &outcome);
  EXPECT_EQ(status.code(), Status::Code::kIo) << status.ToString();
  EXPECT_NE(status.message().find("temporary directory"), std::string::npos) << status.ToString();
  EXPECT_FALSE(ran);
}

}  // namespace
}  // namespace pba
