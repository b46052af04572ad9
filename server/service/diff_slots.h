// DiffSlots: how many shape comparisons (DiffRevisions, geometry_diff.h) run
// at once. Each may take up to kMaxDiffVoxels' memory (a few hundred MB),
// so the rest wait their turn, and give up when their caller goes or the
// server stops. Header only: the service holds one, and pba-server's main
// sees the service's header without the solver's include paths.
#pragma once

#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>

#include "pba/status.h"

namespace pba {

class DiffSlots {
 public:
  explicit DiffSlots(int slots) : free_(slots) {}

  // Takes a slot, waiting up to `patience` and asking `cancelled` (may be
  // empty) every 50 ms while it waits: Status::Cancelled when it says so;
  // kFailedPrecondition with field "diff_slots" (the service answers
  // RESOURCE_EXHAUSTED) when no slot frees in time.
  Status Acquire(const std::function<bool()>& cancelled, std::chrono::milliseconds patience) {
    const auto deadline = std::chrono::steady_clock::now() + patience;
    std::unique_lock lock(mutex_);
    while (free_ == 0) {
      if (cancelled && cancelled()) {
        return Status::Cancelled("the comparison was cancelled while it waited for its turn");
      }
      if (std::chrono::steady_clock::now() >= deadline) {
        return Status::ResourceExhausted(
            "diff_slots", "the server is busy comparing other revisions' shapes; try again later");
      }
      freed_.wait_for(lock, std::chrono::milliseconds(50));
    }
    --free_;
    return Status::Ok();
  }

  void Release() {
    {
      std::lock_guard lock(mutex_);
      ++free_;
    }
    freed_.notify_one();
  }

 private:
  std::mutex mutex_;
  std::condition_variable freed_;
  int free_;  // guarded by mutex_
};

}  // namespace pba
