#include "jobs/solver_process.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace pba {
namespace {

// A line longer than this is handed over in pieces rather than buffered
// without bound (a runaway child must not exhaust the server's memory).
constexpr size_t kMaxLine = 1 << 20;

void CloseFd(int* fd) {
  if (*fd >= 0) ::close(*fd);
  *fd = -1;
}

// Everything between fork and exec must be async-signal-safe: the server is
// multithreaded and another thread may have held a lock (malloc's) at fork.
[[noreturn]] void ExecChild(const char* program, char* const argv[], int stdin_fd, int stdout_fd,
                            int stderr_fd, int error_fd, pid_t parent, int64_t max_address_space) {
  ::setpgid(0, 0);
  struct rlimit no_core = {0, 0};
  ::setrlimit(RLIMIT_CORE, &no_core);
  if (max_address_space > 0) {
    struct rlimit space = {static_cast<rlim_t>(max_address_space),
                           static_cast<rlim_t>(max_address_space)};
    ::setrlimit(RLIMIT_AS, &space);
  }
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);
  // The parent may have died before prctl took effect.
  if (::getppid() != parent) ::_exit(127);
  // The server blocks SIGTERM/SIGINT in every thread (a sigwait thread takes
  // them) and the mask survives exec: unblock, or pba-solve could not be
  // cancelled. Ignored signals also survive exec; restore the defaults.
  sigset_t none;
  sigemptyset(&none);
  ::sigprocmask(SIG_SETMASK, &none, nullptr);
  struct sigaction action;
  std::memset(&action, 0, sizeof(action));
  action.sa_handler = SIG_DFL;
  for (int sig : {SIGPIPE, SIGTERM, SIGINT, SIGHUP}) ::sigaction(sig, &action, nullptr);

  if (::dup2(stdin_fd, STDIN_FILENO) < 0 || ::dup2(stdout_fd, STDOUT_FILENO) < 0 ||
      ::dup2(stderr_fd, STDERR_FILENO) < 0) {
    const int error = errno;
    [[maybe_unused]] ssize_t n = ::write(error_fd, &error, sizeof(error));
    ::_exit(127);
  }
  ::execv(program, argv);
  const int error = errno;
  [[maybe_unused]] ssize_t n = ::write(error_fd, &error, sizeof(error));
  ::_exit(127);
}

}  // namespace

std::string SignalName(int signal) {
  const char* abbrev = ::sigabbrev_np(signal);
  return abbrev != nullptr ? std::string("SIG") + abbrev : "signal " + std::to_string(signal);
}

SolverProcess::~SolverProcess() {
  if (pid_ > 0 && !reaped_) {
    ::kill(-pid_, SIGKILL);
    int status = 0;
    while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
    }
  }
  CloseFd(&stdout_fd_);
}

Status SolverProcess::Start(const SolverCommand& command) {
  // Prepared before fork: the child may not allocate.
  std::vector<std::string> strings;
  strings.push_back(command.program.string());
  strings.insert(strings.end(), command.args.begin(), command.args.end());
  std::vector<char*> argv;
  for (std::string& s : strings) argv.push_back(s.data());
  argv.push_back(nullptr);

  int log_fd = ::open(command.stderr_log.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (log_fd < 0) {
    return Status::Io("cannot open " + command.stderr_log.string() + ": " + std::strerror(errno));
  }
  int null_fd = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
  int out_pipe[2] = {-1, -1};
  // The exec-error pipe is close-on-exec: the parent reads EOF when exec
  // succeeded and the child's errno when it did not.
  int error_pipe[2] = {-1, -1};
  if (null_fd < 0 || ::pipe2(out_pipe, O_CLOEXEC) != 0 || ::pipe2(error_pipe, O_CLOEXEC) != 0) {
    const std::string error = std::strerror(errno);
    for (int* fd :
         {&log_fd, &null_fd, &out_pipe[0], &out_pipe[1], &error_pipe[0], &error_pipe[1]}) {
      CloseFd(fd);
    }
    return Status::Io("cannot create pipes for the solver: " + error);
  }

  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid == 0) {
    ExecChild(argv[0], argv.data(), null_fd, out_pipe[1], log_fd, error_pipe[1], parent,
              command.max_address_space_bytes);
  }
  const int fork_errno = errno;
  CloseFd(&log_fd);
  CloseFd(&null_fd);
  CloseFd(&out_pipe[1]);
  CloseFd(&error_pipe[1]);
  if (pid < 0) {
    CloseFd(&out_pipe[0]);
    CloseFd(&error_pipe[0]);
    return Status::Io(std::string("cannot fork: ") + std::strerror(fork_errno));
  }
  // Also set the group from the parent: whichever runs first, the group
  // exists before anyone signals it.
  ::setpgid(pid, pid);
  pid_ = pid;
  stdout_fd_ = out_pipe[0];

  int child_errno = 0;
  ssize_t n;
  do {
    n = ::read(error_pipe[0], &child_errno, sizeof(child_errno));
  } while (n < 0 && errno == EINTR);
  CloseFd(&error_pipe[0]);
  if (n > 0) {
    int status = 0;
    while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
    }
    reaped_ = true;
    CloseFd(&stdout_fd_);
    return Status::Io("cannot run " + command.program.string() + ": " + std::strerror(child_errno));
  }
  return Status::Ok();
}

SolverProcess::ReadResult SolverProcess::ReadLine(std::string* line,
                                                  std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (true) {
    const size_t newline = buffer_.find('\n');
    if (newline != std::string::npos || buffer_.size() >= kMaxLine ||
        (stdout_closed_ && !buffer_.empty())) {
      const size_t take = newline != std::string::npos ? newline : buffer_.size();
      line->assign(buffer_, 0, take);
      buffer_.erase(0, newline != std::string::npos ? take + 1 : take);
      return ReadResult::kLine;
    }
    if (stdout_closed_) return ReadResult::kEnd;

    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    pollfd fd{stdout_fd_, POLLIN, 0};
    const int ready = ::poll(&fd, 1, static_cast<int>(std::max<int64_t>(0, left.count())));
    if (ready < 0 && errno == EINTR) continue;
    if (ready == 0) return ReadResult::kTimeout;
    char chunk[65536];
    const ssize_t n = ::read(stdout_fd_, chunk, sizeof(chunk));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      stdout_closed_ = true;
      CloseFd(&stdout_fd_);
    } else {
      buffer_.append(chunk, static_cast<size_t>(n));
    }
  }
}

void SolverProcess::Signal(int signal) {
  if (pid_ > 0 && !reaped_) ::kill(-pid_, signal);
}

bool SolverProcess::TryWait(ProcessExit* exit) {
  if (pid_ <= 0) return false;
  if (!reaped_) {
    int status = 0;
    pid_t r;
    do {
      r = ::waitpid(pid_, &status, WNOHANG);
    } while (r < 0 && errno == EINTR);
    if (r == 0) return false;
    reaped_ = true;
    if (r > 0 && WIFSIGNALED(status)) {
      exit_.signaled = true;
      exit_.signal = WTERMSIG(status);
    } else if (r > 0) {
      exit_.code = WEXITSTATUS(status);
    } else {
      exit_.code = -1;  // ECHILD: someone else reaped it (SIGCHLD ignored)
    }
  }
  *exit = exit_;
  return true;
}

}  // namespace pba
