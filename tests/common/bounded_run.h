// Runs a piece of a test in a forked child with a small address-space
// limit and an alarm, so that a test of a reader with hostile bytes fails
// (rather than swaps or hangs) when the reader allocates what a header
// announces or walks an exponential structure.
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <functional>
#include <new>

namespace pba::test {

enum BoundedRunResult : int {
  kWorkTrue = 0,
  kWorkFalse = 1,
  kOutOfMemory = 2,  // std::bad_alloc (or length_error) under the limit
  kOutOfTime = 3,    // the alarm went off
  kCrashed = 4,      // another signal or exit
};

// The address space this process has mapped [bytes], from /proc/self/statm.
inline int64_t MappedBytesForTest() {
  const int fd = ::open("/proc/self/statm", O_RDONLY);
  if (fd < 0) return 0;
  char text[64] = {};
  const ssize_t n = ::read(fd, text, sizeof text - 1);
  ::close(fd);
  int64_t pages = 0;
  for (ssize_t i = 0; i < n && text[i] >= '0' && text[i] <= '9'; ++i) {
    pages = pages * 10 + (text[i] - '0');
  }
  return pages * ::sysconf(_SC_PAGESIZE);
}

// `work` in a child that may map at most `extra_bytes` more than this
// process has and run at most `seconds`.
inline BoundedRunResult RunBounded(int64_t extra_bytes, unsigned seconds,
                                   const std::function<bool()>& work) {
  const pid_t pid = ::fork();
  if (pid < 0) return kCrashed;
  if (pid == 0) {
    struct rlimit no_core = {0, 0};
    ::setrlimit(RLIMIT_CORE, &no_core);
    const rlim_t cap = static_cast<rlim_t>(MappedBytesForTest() + extra_bytes);
    struct rlimit space = {cap, cap};
    ::setrlimit(RLIMIT_AS, &space);
    ::alarm(seconds);
    int code = kWorkFalse;
    try {
      code = work() ? kWorkTrue : kWorkFalse;
    } catch (const std::bad_alloc&) {
      code = kOutOfMemory;
    } catch (const std::length_error&) {
      code = kOutOfMemory;
    }
    ::_exit(code);
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
  }
  if (WIFSIGNALED(status)) return WTERMSIG(status) == SIGALRM ? kOutOfTime : kCrashed;
  const int code = WEXITSTATUS(status);
  return code <= kOutOfMemory ? static_cast<BoundedRunResult>(code) : kCrashed;
}

}  // namespace pba::test
