#include "jobs/solver_process.h"

#include <gtest/gtest.h>
#include <signal.h>

#include <fstream>
#include <sstream>

#include "unit/server/server_test_support.h"

namespace pba {
namespace {

using testing::TempDir;

std::filesystem::path WriteScript(const std::filesystem::path& dir, const std::string& body) {
  const std::filesystem::path path = dir / "script";
  std::ofstream(path) << "#!/bin/sh\n" << body;
  std::filesystem::permissions(path, std::filesystem::perms::owner_all);
  return path;
}

std::string ReadFile(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream content;
  content << in.rdbuf();
  return content.str();
}

ProcessExit WaitForExit(SolverProcess& process) {
  ProcessExit exit;
  EXPECT_TRUE(testing::WaitUntil([&] { return process.TryWait(&exit); }));
  return exit;
}

TEST(SolverProcessTest, ReadsLinesAndLogsStderr) {
  TempDir dir;
  SolverCommand command;
  command.program =
      WriteScript(dir.path(), "echo one\necho oops >&2\nprintf 'two\\nthree'\nexit 7\n");
  command.stderr_log = dir.path() / "solve.log";
  SolverProcess process;
  ASSERT_TRUE(process.Start(command).ok());
  std::vector<std::string> lines;
  std::string line;
  SolverProcess::ReadResult read;
  while ((read = process.ReadLine(&line, std::chrono::seconds(5))) !=
         SolverProcess::ReadResult::kEnd) {
    ASSERT_EQ(read, SolverProcess::ReadResult::kLine);
    lines.push_back(line);
  }
  EXPECT_EQ(lines, (std::vector<std::string>{"one", "two", "three"}));
  const ProcessExit exit = WaitForExit(process);
  EXPECT_FALSE(exit.signaled);
  EXPECT_EQ(exit.code, 7);
  EXPECT_EQ(ReadFile(command.stderr_log), "oops\n");
}

TEST(SolverProcessTest, PassesArguments) {
  TempDir dir;
  SolverCommand command;
  command.program = WriteScript(dir.path(), "for a in \"$@\"; do echo \"[$a]\"; done\n");
  command.args = {"a b", "--out", "*"};
  command.stderr_log = dir.path() / "solve.log";
  SolverProcess process;
  ASSERT_TRUE(process.Start(command).ok());
  std::vector<std::string> lines;
  std::string line;
  while (process.ReadLine(&line, std::chrono::seconds(5)) == SolverProcess::ReadResult::kLine) {
    lines.push_back(line);
  }
  EXPECT_EQ(lines, (std::vector<std::string>{"[a b]", "[--out]", "[*]"}));
  WaitForExit(process);
}

TEST(SolverProcessTest, SignalReachesTheWholeGroup) {
  TempDir dir;
  SolverCommand command;
  // The shell waits on a child; both must go when the group is signalled.
  // "started" comes only once the child exists. Printed before a foreground
  // command, it let the signal land while the shell was still forking; a
  // shell that holds signals blocked across its fork then dies alone and the
  // new child keeps stdout open, so the test failed now and then.
  command.program = WriteScript(dir.path(), "sleep 30 &\necho started\nwait\n");
  command.stderr_log = dir.path() / "solve.log";
  SolverProcess process;
  ASSERT_TRUE(process.Start(command).ok());
  std::string line;
  ASSERT_EQ(process.ReadLine(&line, std::chrono::seconds(5)), SolverProcess::ReadResult::kLine);
  EXPECT_EQ(::getpgid(process.pid()), process.pid());
  process.Signal(SIGTERM);
  const ProcessExit exit = WaitForExit(process);
  EXPECT_TRUE(exit.signaled);
  EXPECT_EQ(exit.signal, SIGTERM);
  // stdout closes once sleep is gone too.
  EXPECT_EQ(process.ReadLine(&line, std::chrono::seconds(5)), SolverProcess::ReadResult::kEnd);
}

TEST(SolverProcessTest, UnblocksSignalsBlockedInTheServer) {
  TempDir dir;
  sigset_t blocked, previous;
  sigemptyset(&blocked);
  sigaddset(&blocked, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &blocked, &previous);
  SolverCommand command;
  command.program = WriteScript(dir.path(), "echo started\nexec sleep 30\n");
  command.stderr_log = dir.path() / "solve.log";
  SolverProcess process;
  ASSERT_TRUE(process.Start(command).ok());
  pthread_sigmask(SIG_SETMASK, &previous, nullptr);
  std::string line;
  ASSERT_EQ(process.ReadLine(&line, std::chrono::seconds(5)), SolverProcess::ReadResult::kLine);
  process.Signal(SIGTERM);
  const ProcessExit exit = WaitForExit(process);
  EXPECT_TRUE(exit.signaled);
  EXPECT_EQ(exit.signal, SIGTERM);
}

TEST(SolverProcessTest, MissingProgramFailsToStart) {
  TempDir dir;
  SolverCommand command;
  command.program = dir.path() / "does-not-exist";
  command.stderr_log = dir.path() / "solve.log";
  SolverProcess process;
  const Status status = process.Start(command);
  EXPECT_FALSE(status.ok());
  EXPECT_NE(status.message().find("does-not-exist"), std::string::npos) << status.message();
}

TEST(SolverProcessTest, DestructorKillsARunningChild) {
  TempDir dir;
  SolverCommand command;
  command.program = WriteScript(dir.path(), "trap '' TERM\necho started\nexec sleep 30\n");
  command.stderr_log = dir.path() / "solve.log";
  pid_t pid = 0;
  {
    SolverProcess process;
    ASSERT_TRUE(process.Start(command).ok());
    pid = process.pid();
    std::string line;
    ASSERT_EQ(process.ReadLine(&line, std::chrono::seconds(5)), SolverProcess::ReadResult::kLine);
  }
  EXPECT_NE(::kill(pid, 0), 0);  // gone and reaped
}

TEST(SolverProcessTest, NamesSignals) {
  EXPECT_EQ(SignalName(SIGKILL), "SIGKILL");
  EXPECT_EQ(SignalName(SIGTERM), "SIGTERM");
}

}  // namespace
}  // namespace pba
