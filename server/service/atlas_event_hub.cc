#include "service/atlas_event_hub.h"

namespace pba {

AtlasEventHub::Subscription::~Subscription() { hub_.Unsubscribe(this); }

bool AtlasEventHub::Subscription::Next(std::chrono::milliseconds timeout,
                                       std::vector<v1::AtlasEvent>* events, bool* overrun) {
  events->clear();
  std::unique_lock lock(hub_.mutex_);
  hub_.changed_.wait_for(lock, timeout,
                         [&] { return !queue_.empty() || overrun_ || hub_.shutting_down_; });
  *overrun = overrun_;
  if (overrun_ || hub_.shutting_down_) return false;
  events->assign(std::make_move_iterator(queue_.begin()), std::make_move_iterator(queue_.end()));
  queue_.clear();
  return true;
}

std::unique_ptr<AtlasEventHub::Subscription> AtlasEventHub::Subscribe(const std::string& project) {
  std::unique_ptr<Subscription> subscription(new Subscription(*this, project));
  std::lock_guard lock(mutex_);
  subscribers_.emplace(project, subscription.get());
  return subscription;
}

void AtlasEventHub::Unsubscribe(Subscription* subscription) {
  std::lock_guard lock(mutex_);
  auto [begin, end] = subscribers_.equal_range(subscription->project_);
  for (auto it = begin; it != end; ++it) {
    if (it->second == subscription) {
      subscribers_.erase(it);
      return;
    }
  }
}

void AtlasEventHub::Publish(const v1::AtlasEvent& event) {
  {
    std::lock_guard lock(mutex_);
    auto [begin, end] = subscribers_.equal_range(event.project());
    for (auto it = begin; it != end; ++it) {
      Subscription& subscription = *it->second;
      if (subscription.overrun_) continue;
      if (subscription.queue_.size() >= kMaxQueued) {
        subscription.overrun_ = true;
        subscription.queue_.clear();
        continue;
      }
      subscription.queue_.push_back(event);
    }
  }
  changed_.notify_all();
}

void AtlasEventHub::Shutdown() {
  {
    std::lock_guard lock(mutex_);
    shutting_down_ = true;
  }
  changed_.notify_all();
}

bool AtlasEventHub::shutting_down() const {
  std::lock_guard lock(mutex_);
  return shutting_down_;
}

size_t AtlasEventHub::subscribers() const {
  std::lock_guard lock(mutex_);
  return subscribers_.size();
}

}  // namespace pba
