#include "jobs/job_event_hub.h"

namespace pba {

void JobEventHub::Publish(const v1::JobEvent& event) {
  {
    std::lock_guard lock(mutex_);
    ++version_;
    if (event.state() == v1::Job::RUNNING) {
      JobLive& live = jobs_[event.job_id()];
      live.recent.push_back(event);
      if (live.recent.size() > kRecentPerJob) live.recent.pop_front();
      live.phase = event.phase();
      live.progress = event.progress();
    } else {
      jobs_.erase(event.job_id());
    }
  }
  changed_.notify_all();
  const bool state_change = event.state() != v1::Job::RUNNING || event.phase().empty();
  if (state_change && state_listener_) state_listener_(event);
}

std::vector<v1::JobEvent> JobEventHub::Recent(const std::string& job_id,
                                              int64_t after_sequence) const {
  std::vector<v1::JobEvent> events;
  std::lock_guard lock(mutex_);
  auto it = jobs_.find(job_id);
  if (it == jobs_.end()) return events;
  for (const v1::JobEvent& event : it->second.recent) {
    if (event.sequence() > after_sequence) events.push_back(event);
  }
  return events;
}

bool JobEventHub::Live(const std::string& job_id, std::string* phase, double* progress) const {
  std::lock_guard lock(mutex_);
  auto it = jobs_.find(job_id);
  if (it == jobs_.end()) return false;
  *phase = it->second.phase;
  *progress = it->second.progress;
  return true;
}

uint64_t JobEventHub::version() const {
  std::lock_guard lock(mutex_);
  return version_;
}

void JobEventHub::WaitForChange(uint64_t seen, std::chrono::milliseconds timeout) const {
  std::unique_lock lock(mutex_);
  changed_.wait_for(lock, timeout, [&] { return version_ != seen || shutting_down_; });
}

void JobEventHub::Shutdown() {
  {
    std::lock_guard lock(mutex_);
    shutting_down_ = true;
    ++version_;
  }
  changed_.notify_all();
}

bool JobEventHub::shutting_down() const {
  std::lock_guard lock(mutex_);
  return shutting_down_;
}

}  // namespace pba
