// Test helpers that run the real executables: a child process with captured
// output, and a pba-server started on an ephemeral loopback port.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace pba::testing {

struct RunResult {
  int exit_code = -1;  // -signal when killed
  std::string out;
  std::string err;
};

// The whole file's bytes ("" when it cannot be read).
std::string ReadFile(const std::filesystem::path& path);

// How often `what` occurs in `text` (overlapping occurrences counted).
std::size_t CountOf(const std::string& text, const std::string& what);

// The path of program `name` in a directory of PATH (/usr/bin without
// one); empty when there is none. RunProcess does not search PATH.
std::string FindProgram(const std::string& name);

// Runs `argv` to completion (killed after `timeout`), capturing stdout and stderr.
RunResult RunProcess(const std::vector<std::string>& argv,
                     std::chrono::seconds timeout = std::chrono::seconds(120));
// The same with `env` ("NAME=VALUE" entries) added to this process's
// environment for the child only. Unlike setenv before RunProcess, it is safe
// from several threads at once, each child with its own user's PBA_TOKEN.
RunResult RunProcess(const std::vector<std::string>& argv, const std::vector<std::string>& env,
                     std::chrono::seconds timeout = std::chrono::seconds(120));

// A pba-server child on 127.0.0.1 with its own data directory.
class ServerProcess {
 public:
  ServerProcess(std::filesystem::path binary, std::filesystem::path data_dir);
  ~ServerProcess();  // SIGKILL if still running
  ServerProcess(const ServerProcess&) = delete;
  ServerProcess& operator=(const ServerProcess&) = delete;

  // Starts the server on a free port, with `extra_args` after --data and
  // --listen (e.g. {"--max-running", "2"}); false (with the log) if it did
  // not report its address within 20 s.
  bool Start(std::string* log, const std::vector<std::string>& extra_args = {});
  // Starts of this server run under a file-size limit (RLIMIT_FSIZE, as
  // `ulimit -f`) of `bytes`; 0: none (the default).
  void set_file_size_limit(int64_t bytes) { file_size_limit_ = bytes; }
  // SIGTERM and wait; returns the exit code (-signal if killed).
  int Stop(std::chrono::seconds timeout = std::chrono::seconds(30));
  // SIGKILL and reap, like a crash.
  void Kill();

  const std::string& address() const { return address_; }
  pid_t pid() const { return pid_; }
  std::filesystem::path log_path() const { return data_dir_ / "server-test.log"; }

 private:
  std::filesystem::path binary_;
  std::filesystem::path data_dir_;
  pid_t pid_ = -1;
  std::string address_;
  int64_t file_size_limit_ = 0;
};

// Children of `parent` whose command name is `name`.
std::vector<pid_t> ChildrenNamed(pid_t parent, const std::string& name);

// A fresh empty directory under the system temp dir, removed by the destructor.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace pba::testing
