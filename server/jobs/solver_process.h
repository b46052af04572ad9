// SolverProcess: one pba-solve child, started with fork/exec (no shell).
//
// The child runs in its own process group, so a signal reaches pba-solve and
// anything it starts, and never the server's group. It gets
// PR_SET_PDEATHSIG(SIGKILL): if the server dies, the kernel kills the child
// instead of leaving an orphan solve running. Note the death signal fires when
// the *thread* that forked exits, so a SolverProcess must be started by a
// thread that outlives it (the executor's workers do).
//
// stdin is /dev/null, stdout is a pipe read line by line (the SolveEvent
// protocol), stderr is appended to a log file.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "pba/status.h"

namespace pba {

struct SolverCommand {
  std::filesystem::path program;
  std::vector<std::string> args;  // without argv[0]
  std::filesystem::path stderr_log;
  // Resource limits of the child (setrlimit), 0: none. Address space
  // [bytes]: a solve that asks for more gets allocation failures and ends
  // with an error instead of pushing the server into swap. No core files
  // either way (a crashed solve of a large model would write gigabytes).
  int64_t max_address_space_bytes = 0;
};

// How a child ended.
struct ProcessExit {
  bool signaled = false;
  int code = 0;    // exit code when !signaled
  int signal = 0;  // terminating signal when signaled
};

class SolverProcess {
 public:
  enum class ReadResult { kLine, kTimeout, kEnd };

  SolverProcess() = default;
  SolverProcess(const SolverProcess&) = delete;
  SolverProcess& operator=(const SolverProcess&) = delete;
  // A child still running is killed (SIGKILL to its group) and reaped: a
  // SolverProcess never leaks a process or a zombie.
  ~SolverProcess();

  // Starts the child. Fails (with nothing left running) when the log cannot
  // be opened, or the program cannot be executed.
  Status Start(const SolverCommand& command);

  pid_t pid() const { return pid_; }

  // The next complete line of the child's stdout, without its newline,
  // waiting at most `timeout`. kEnd once stdout is closed and drained.
  ReadResult ReadLine(std::string* line, std::chrono::milliseconds timeout);

  // Sends `signal` to the child's process group; a no-op once reaped (the
  // pid may then belong to someone else).
  void Signal(int signal);

  // Non-blocking: true (and *exit) once the child has exited.
  bool TryWait(ProcessExit* exit);

 private:
  pid_t pid_ = -1;
  int stdout_fd_ = -1;
  bool stdout_closed_ = false;
  bool reaped_ = false;
  ProcessExit exit_;
  std::string buffer_;
};

// "SIGKILL" for 9, "signal 77" for a number without a name.
std::string SignalName(int signal);

}  // namespace pba
