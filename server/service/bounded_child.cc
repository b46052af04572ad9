#include "service/bounded_child.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <stdlib.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <new>

#include "jobs/solver_process.h"

namespace pba {
namespace fs = std::filesystem;
namespace {

constexpr size_t kMaxAnswerBytes = size_t{1} << 20;

// A private temporary directory, removed with whatever is in it.
class ScratchDir {
 public:
  ScratchDir() {
    std::error_code ec;  // a TMPDIR that is not a directory: no scratch, not a throw
    const fs::path tmp = fs::temp_directory_path(ec);
    if (ec) return;
    std::string pattern = (tmp / "pba-check-XXXXXX").string();
    if (::mkdtemp(pattern.data()) != nullptr) path_ = pattern;
  }
  ~ScratchDir() {
    std::error_code ignored;
    if (!path_.empty()) fs::remove_all(path_, ignored);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

class Fd {
 public:
  explicit Fd(int fd = -1) : fd_(fd) {}
  ~Fd() { Close(); }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  int get() const { return fd_; }
  void Close() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }

 private:
  int fd_;
};

// The address space this process has mapped [bytes] (/proc/self/statm's
// first field, in pages), read without allocating; 0 when unknown.
int64_t MappedBytes() {
  const int fd = ::open("/proc/self/statm", O_RDONLY | O_CLOEXEC);
  if (fd < 0) return 0;
  char text[64] = {};
  const ssize_t n = ::read(fd, text, sizeof text - 1);
  ::close(fd);
  if (n <= 0) return 0;
  int64_t pages = 0;
  for (ssize_t i = 0; i < n && text[i] >= '0' && text[i] <= '9'; ++i) {
    pages = pages * 10 + (text[i] - '0');
  }
  return pages * ::sysconf(_SC_PAGESIZE);
}

void WriteAllFd(int fd, const char* data, size_t size) {
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return;
    data += n;
    size -= static_cast<size_t>(n);
  }
}

// The answer: one byte End, one byte Status::Code, then field, message and
// output, each as a 4-byte length and its bytes.
void AppendString(std::string* out, const std::string& s) {
  const uint32_t size = static_cast<uint32_t>(std::min(s.size(), kMaxAnswerBytes));
  out->append(reinterpret_cast<const char*>(&size), 4);
  out->append(s.data(), size);
}

bool ReadString(const std::string& in, size_t* pos, std::string* s) {
  uint32_t size = 0;
  if (in.size() < *pos + 4) return false;
  std::memcpy(&size, in.data() + *pos, 4);
  *pos += 4;
  if (in.size() < *pos + size) return false;
  s->assign(in, *pos, size);
  *pos += size;
  return true;
}

Status MakeStatus(Status::Code code, std::string field, std::string message) {
  using Code = Status::Code;
  switch (code) {
    case Code::kOk:
      return Status::Ok();
    case Code::kInvalidArgument:
      return Status::InvalidArgument(std::move(field), std::move(message));
    case Code::kFailedPrecondition:
      return Status::FailedPrecondition(std::move(field), std::move(message));
    case Code::kNumerical:
      return Status::Numerical(std::move(message));
    case Code::kIo:
      return Status::Io(std::move(message));
    case Code::kCancelled:
      return Status::Cancelled(std::move(message));
    case Code::kNotFound:
      return Status::NotFound(std::move(message));
    case Code::kAlreadyExists:
      return Status::AlreadyExists(std::move(message));
    case Code::kAborted:
      return Status::Aborted(std::move(message));
    case Code::kPermissionDenied:
      return Status::PermissionDenied(std::move(message));
    case Code::kUnauthenticated:
      return Status::Unauthenticated(std::move(message));
    case Code::kOutOfRange:
      return Status::OutOfRange(std::move(field), std::move(message));
    case Code::kResourceExhausted:
      return Status::ResourceExhausted(std::move(field), std::move(message));
    case Code::kInternal:
      break;
  }
  return Status::Internal(std::move(message));
}

[[noreturn]] void RunChild(const ChildLimits& limits,
                           const std::function<Status(std::string* output)>& work, int answer_fd,
                           pid_t parent, const char* scratch) {
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (::getppid() != parent) ::_exit(127);
  struct rlimit no_core = {0, 0};
  ::setrlimit(RLIMIT_CORE, &no_core);
  ::setenv("TMPDIR", scratch, 1);
  const int64_t mapped = MappedBytes();
  if (mapped > 0 && limits.memory_bytes > 0) {
    const rlim_t cap = static_cast<rlim_t>(mapped + limits.memory_bytes);
    struct rlimit space = {cap, cap};
    ::setrlimit(RLIMIT_AS, &space);
  }
  ChildOutcome::End end = ChildOutcome::End::kDone;
  Status status;
  std::string output;
  try {
    status = work(&output);
  } catch (const std::bad_alloc&) {
    end = ChildOutcome::End::kOutOfMemory;
  } catch (const std::length_error&) {  // a vector asked for more than it can hold
    end = ChildOutcome::End::kOutOfMemory;
  }
  if (end != ChildOutcome::End::kDone) {
    status = Status::Ok();
    output.clear();
    output.shrink_to_fit();
  }
  try {
    std::string answer;
    answer.push_back(static_cast<char>(end));
    answer.push_back(static_cast<char>(status.code()));
    AppendString(&answer, status.field());
    AppendString(&answer, status.message());
    AppendString(&answer, output);
    WriteAllFd(answer_fd, answer.data(), answer.size());
  } catch (const std::bad_alloc&) {
    const char answer[2] = {static_cast<char>(ChildOutcome::End::kOutOfMemory), 0};
    WriteAllFd(answer_fd, answer, sizeof answer);
  }
  ::_exit(0);
}

std::string Seconds(std::chrono::milliseconds time) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", static_cast<double>(time.count()) / 1000);
  return text;
}

}  // namespace

Status RunInBoundedChild(const ChildLimits& limits,
                         const std::function<Status(std::string* output)>& work,
                         ChildOutcome* outcome) {
  *outcome = ChildOutcome();
  const ScratchDir scratch;
  if (scratch.path().empty()) return Status::Io("cannot create a temporary directory");
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) return Status::Io("cannot create a pipe");
  Fd read_end(fds[0]), write_end(fds[1]);
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) return Status::Internal(std::string("fork failed: ") + std::strerror(errno));
  if (pid == 0) {
    ::close(fds[0]);
    RunChild(limits, work, fds[1], parent, scratch.path().c_str());
  }
  write_end.Close();

  // The answer until the child closes the pipe, or the time is up.
  const auto deadline = std::chrono::steady_clock::now() + limits.time;
  std::string answer;
  bool timed_out = false;
  while (true) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) {
      timed_out = true;
      break;
    }
    struct pollfd p = {read_end.get(), POLLIN, 0};
    const int ready = ::poll(&p, 1, static_cast<int>(std::min<int64_t>(left.count(), 1000)));
    if (ready < 0 && errno != EINTR) break;
    if (ready <= 0) continue;
    char buffer[65536];
    const ssize_t n = ::read(read_end.get(), buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    if (answer.size() < 3 * kMaxAnswerBytes + 16) answer.append(buffer, static_cast<size_t>(n));
  }
  if (timed_out) ::kill(pid, SIGKILL);
  int wait_status = 0;
  while (::waitpid(pid, &wait_status, 0) < 0 && errno == EINTR) {
  }
  if (timed_out) {
    outcome->end = ChildOutcome::End::kOutOfTime;
    return Status::Ok();
  }
  size_t pos = 2;
  std::string field, message;
  if (answer.size() >= 2) {
    outcome->end = static_cast<ChildOutcome::End>(answer[0]);
    if (outcome->end != ChildOutcome::End::kDone) return Status::Ok();
    if (ReadString(answer, &pos, &field) && ReadString(answer, &pos, &message) &&
        ReadString(answer, &pos, &outcome->output)) {
      outcome->status = MakeStatus(static_cast<Status::Code>(answer[1]), field, message);
      return Status::Ok();
    }
  }
  outcome->end = ChildOutcome::End::kCrashed;
  outcome->detail = WIFSIGNALED(wait_status)
                        ? SignalName(WTERMSIG(wait_status))
                        : "exit code " + std::to_string(WEXITSTATUS(wait_status));
  return Status::Ok();
}

Status OutcomeStatus(const ChildOutcome& outcome, const ChildLimits& limits,
                     const std::string& field, const std::string& what) {
  switch (outcome.end) {
    case ChildOutcome::End::kDone:
      return outcome.status;
    case ChildOutcome::End::kOutOfMemory:
      return Status::InvalidArgument(
          field, what + " needs more than " + std::to_string(limits.memory_bytes >> 20) +
                     " MiB to check (a header or a compressed stream announcing more data "
                     "than it holds?)");
    case ChildOutcome::End::kOutOfTime:
      return Status::InvalidArgument(
          field, what + " took longer than " + Seconds(limits.time) + " s to check");
    case ChildOutcome::End::kCrashed:
      break;
  }
  return Status::InvalidArgument(
      field,
      what + " could not be checked (the checking process ended with " + outcome.detail + ")");
}

}  // namespace pba
