// A short command run to its end with its output captured: the cluster
// scheduler's own tools (sbatch, squeue, sacct, scancel) as the Slurm
// executor calls them. No shell: the arguments go to the program as they
// are. stdin is /dev/null; stdout and stderr are read, each up to a bound
// (what is past it is dropped, and said so); a command still running at
// its time limit is killed (SIGKILL to its process group) and reaped.
#pragma once

#include <chrono>
#include <cstddef>
#include <string>
#include <vector>

#include "pba/status.h"

namespace pba {

struct CommandResult {
  bool timed_out = false;
  bool signaled = false;
  int code = 0;    // exit code when it exited
  int signal = 0;  // the signal that ended it otherwise
  std::string out, err;
  bool truncated = false;  // stdout or stderr went past the bound

  bool ok() const { return !timed_out && !signaled && code == 0; }
  // How it ended, for a message: "exit code 1: <first line of stderr>",
  // "killed after 30 s", "ended by SIGSEGV".
  std::string Describe() const;
};

struct CommandOptions {
  std::chrono::milliseconds timeout{30000};
  std::size_t max_output_bytes = std::size_t{64} << 20;  // each of stdout, stderr
  // Extra environment entries ("NAME=value"), over the server's own.
  std::vector<std::string> env;
};

// Runs argv[0] (looked up on PATH when it has no slash) with argv[1..].
// Fails (kFailedPrecondition) only when it cannot be started (not found,
// not executable); every way it ends is in *result.
Status RunCommand(const std::vector<std::string>& argv, const CommandOptions& options,
                  CommandResult* result);

}  // namespace pba
