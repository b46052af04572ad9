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
#include <string>
#include <utility>

#include "pba/status.h"

namespace pba {

class DiffSlots {
 public:
  // `field` and `work` name the bound and the work in the messages (the
  // surface views' builds share the class).
  explicit DiffSlots(int slots, std::string field = "diff_slots",
                     std::string work = "comparing other revisions' shapes")
      : free_(slots), field_(std::move(field)), work_(std::move(work)) {}

  // Takes a slot, waiting up to `patience` and asking `cancelled` (may be
  // empty) every 50 ms while it waits: Status::Cancelled when it says so;
  // ResourceExhausted naming the bound (`field`) when no slot frees in time.
  Status Acquire(const std::function<bool()>& cancelled, std::chrono::milliseconds patience) {
    const auto deadline = std::chrono::steady_clock::now() + patience;
    std::unique_lock lock(mutex_);
    while (free_ == 0) {
      if (cancelled && cancelled()) {
        return Status::Cancelled("cancelled while waiting for its turn");
      }
      if (std::chrono::steady_clock::now() >= deadline) {
        return Status::ResourceExhausted(field_,
                                         "the server is busy " + work_ + "; try again later");
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
  const std::string field_, work_;
};

}  // namespace pba
