// Work on untrusted input in a forked child process with an address-space
// limit and a wall-time limit, so that a hostile file (a header announcing
// gigabytes, a decompression bomb, nested YAML aliases) costs the server a
// clear error rather than its memory or a thread for minutes. The child is
// killed when the time is up; whatever it left in its temporary directory
// (TMPDIR is a private directory for the child) is removed either way.
//
// Fork without exec in a multithreaded server: glibc makes malloc and stdio
// usable in the child (its fork handlers reset their locks), and the work
// uses nothing else that another thread may hold (no logging, no gRPC, no
// database). Should it ever block on such a lock, the wall-time limit ends
// it like any over-long check: the server never waits without bound.
// Nor OpenMP: libgomp's thread pool does not survive fork, and a parallel
// region in a child whose parent ran one may hang. The work run here (the
// contours, surface and NIfTI readers, composing and measuring overlap) has
// no parallel region, and the server runs none itself (solves run in
// pba-solve processes); work that gains one must not run here.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <string>

#include "pba/status.h"

namespace pba {

struct ChildLimits {
  // Address space the child may map beyond what it inherits from the server
  // at fork [bytes] (RLIMIT_AS, set to the inherited size plus this).
  int64_t memory_bytes = int64_t{1024} << 20;
  std::chrono::milliseconds time{30000};
};

struct ChildOutcome {
  enum class End {
    kDone,         // the work returned; `status` and `output` are its own
    kOutOfMemory,  // an allocation failed (std::bad_alloc) under the limit
    kOutOfTime,    // killed at the wall-time limit
    kCrashed,      // ended by a signal or exited without an answer
  };
  End end = End::kDone;
  Status status;
  std::string output;  // what the work wrote to *output (at most 1 MiB)
  std::string detail;  // kCrashed: how it ended ("SIGSEGV", "exit code 3")
};

// Runs `work` in a child under `limits`; `work` returns a Status and may
// fill *output (both are sent back through a pipe). Fails (kInternal or
// kIo) only when the child or its directory cannot be created.
Status RunInBoundedChild(const ChildLimits& limits,
                         const std::function<Status(std::string* output)>& work,
                         ChildOutcome* outcome);

// The outcome as a Status for a user: kDone gives the work's own status;
// the others kInvalidArgument on `field`, `what` the subject of a sentence
// ("the file") - "the file needs more than 1024 MiB to check",
// "... took longer than 30 s to check", "... could not be checked (the
// checking process ended with SIGSEGV)".
Status OutcomeStatus(const ChildOutcome& outcome, const ChildLimits& limits,
                     const std::string& field, const std::string& what);

}  // namespace pba
