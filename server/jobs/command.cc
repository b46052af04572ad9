#include "jobs/command.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cerrno>

#include "jobs/solver_process.h"

extern char** environ;

namespace pba {
namespace {

// Both ends close on exec: the child gets its copies through dup2 only.
struct Pipe {
  int read = -1, write = -1;
  ~Pipe() {
    if (read >= 0) ::close(read);
    if (write >= 0) ::close(write);
  }
  bool Open() {
    int fds[2];
    if (::pipe2(fds, O_CLOEXEC) != 0) return false;
    read = fds[0];
    write = fds[1];
    return true;
  }
  void CloseWrite() {
    if (write >= 0) ::close(write);
    write = -1;
  }
};

// The server's environment with `extra` ("NAME=value") put over it.
std::vector<std::string> Environment(const std::vector<std::string>& extra) {
  std::vector<std::string> env;
  for (char** e = environ; e != nullptr && *e != nullptr; ++e) {
    const std::string entry(*e);
    const std::string name = entry.substr(0, entry.find('=') + 1);
    bool replaced = false;
    for (const std::string& x : extra) replaced |= x.rfind(name, 0) == 0;
    if (!replaced) env.push_back(entry);
  }
  env.insert(env.end(), extra.begin(), extra.end());
  return env;
}

}  // namespace

std::string CommandResult::Describe() const {
  std::string first = err.substr(0, err.find('\n'));
  if (first.empty()) first = out.substr(0, out.find('\n'));
  if (first.size() > 500) first = first.substr(0, 500) + "...";
  std::string how = timed_out  ? "killed at its time limit"
                    : signaled ? std::string("ended by ") + SignalName(signal)
                               : "exit code " + std::to_string(code);
  return first.empty() ? how : how + ": " + first;
}

Status RunCommand(const std::vector<std::string>& argv, const CommandOptions& options,
                  CommandResult* result) {
  *result = CommandResult();
  if (argv.empty()) return Status::InvalidArgument("argv", "no program given");
  Pipe out, err;
  if (!out.Open() || !err.Open()) return Status::Internal("cannot create a pipe");
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_adddup2(&actions, out.write, 1);
  posix_spawn_file_actions_adddup2(&actions, err.write, 2);
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  // Its own process group, so a kill reaches whatever it started; the
  // server's blocked signals not inherited.
  sigset_t none;
  sigemptyset(&none);
  posix_spawnattr_setsigmask(&attributes, &none);
  posix_spawnattr_setpgroup(&attributes, 0);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETPGROUP | POSIX_SPAWN_SETSIGMASK);
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const std::vector<std::string> env = Environment(options.env);
  std::vector<char*> envp;
  for (const std::string& e : env) envp.push_back(const_cast<char*>(e.c_str()));
  envp.push_back(nullptr);
  pid_t pid = -1;
  const int spawned =
      ::posix_spawnp(&pid, argv[0].c_str(), &actions, &attributes, args.data(), envp.data());
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attributes);
  if (spawned != 0) {
    return Status::FailedPrecondition("cannot run " + argv[0] + ": " + ::strerror(spawned));
  }
  out.CloseWrite();
  err.CloseWrite();

  const auto deadline = std::chrono::steady_clock::now() + options.timeout;
  std::array<pollfd, 2> fds = {pollfd{out.read, POLLIN, 0}, pollfd{err.read, POLLIN, 0}};
  std::array<std::string*, 2> sinks = {&result->out, &result->err};
  int open_fds = 2;
  char buffer[65536];
  while (open_fds > 0) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0 && !result->timed_out) {
      result->timed_out = true;
      ::kill(-pid, SIGKILL);
    }
    // After the kill, what is left in the pipes is read without waiting.
    const int ready = ::poll(fds.data(), fds.size(),
                             result->timed_out ? 1000 : static_cast<int>(left.count()) + 1);
    if (ready < 0 && errno != EINTR) break;
    if (ready == 0 && result->timed_out) break;  // a grandchild holds a pipe open
    for (std::size_t i = 0; i < fds.size(); ++i) {
      if (fds[i].fd < 0 || fds[i].revents == 0) continue;
      const ssize_t n = ::read(fds[i].fd, buffer, sizeof buffer);
      if (n > 0) {
        std::string& sink = *sinks[i];
        const std::size_t room =
            options.max_output_bytes - std::min(sink.size(), options.max_output_bytes);
        sink.append(buffer, std::min(room, static_cast<std::size_t>(n)));
        result->truncated |= static_cast<std::size_t>(n) > room;
      } else if (n == 0 || (errno != EINTR && errno != EAGAIN)) {
        fds[i].fd = -1;
        --open_fds;
      }
    }
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFSIGNALED(status)) {
    result->signaled = true;
    result->signal = WTERMSIG(status);
  } else {
    result->code = WEXITSTATUS(status);
  }
  return Status::Ok();
}

}  // namespace pba
