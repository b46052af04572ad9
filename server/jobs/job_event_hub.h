// JobEventHub: where the executor announces job events as they happen and
// WatchJob streams wait for them.
//
// Sequences: every event of a job gets the next sequence number (1, 2, ...),
// whether or not it is stored. State changes and throttled progress (a phase
// change, or >= 5 % more progress) are stored in job_events; the other
// progress events are live only: they are buffered here (the last
// kRecentPerJob of each running job) and appear as gaps when the history is
// read back from the store. A watcher resuming with after_sequence = the last
// number it saw therefore gets every stored event after it, never a
// duplicate. (A hard crash of the server can reuse the numbers of live-only
// events of the job it was running; a clean shutdown cannot.)
//
// The hub also holds the live phase/progress of running jobs, which is newer
// than the stored (throttled) one; GetJob and ListJobs show it.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "pba/v1/job.pb.h"

namespace pba {

class JobEventHub {
 public:
  static constexpr size_t kRecentPerJob = 256;

  // Records `event` and wakes every waiter. An event with a state other than
  // RUNNING ends the job's live data (it must be stored before it is
  // published, so no watcher can miss it).
  void Publish(const v1::JobEvent& event);

  // Called (outside the hub's lock) with every published event that changes
  // a job's state (not progress): the atlas watchers hear of jobs so. Set
  // it before any Publish().
  void SetStateListener(std::function<void(const v1::JobEvent&)> listener) {
    state_listener_ = std::move(listener);
  }

  // Buffered events of `job_id` with sequence > after_sequence, in order.
  std::vector<v1::JobEvent> Recent(const std::string& job_id, int64_t after_sequence) const;

  // The latest live phase/progress of a running job; false if none.
  bool Live(const std::string& job_id, std::string* phase, double* progress) const;

  // A counter that changes with every Publish() and at Shutdown(). Take it
  // before reading, then WaitForChange(it): nothing published in between is
  // missed.
  uint64_t version() const;
  // Waits until version() != seen, Shutdown(), or `timeout`.
  void WaitForChange(uint64_t seen, std::chrono::milliseconds timeout) const;

  // Wakes every waiter for good: streams end when the server stops.
  void Shutdown();
  bool shutting_down() const;

 private:
  std::function<void(const v1::JobEvent&)> state_listener_;

  struct JobLive {
    std::deque<v1::JobEvent> recent;
    std::string phase;
    double progress = 0;
  };

  mutable std::mutex mutex_;
  mutable std::condition_variable changed_;
  uint64_t version_ = 0;
  bool shutting_down_ = false;
  std::map<std::string, JobLive> jobs_;
};

}  // namespace pba
