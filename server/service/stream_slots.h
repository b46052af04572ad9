// StreamSlots: how many long-lived streams (Watch, WatchJob) one user holds
// open at once. Each open stream holds one of the server's threads for as
// long as the caller likes; without a per-user bound, one token (or one
// careless script) could take every thread the server has and lock every
// other user out. The server's thread pool as a whole is bounded too
// (pba_server.cc), so a user at this limit gets a clear answer while
// others are still served. Header only, as diff_slots.h.
#pragma once

#include <map>
#include <mutex>
#include <string>
#include <utility>

namespace pba {

class StreamSlots {
 public:
  explicit StreamSlots(int per_user) : per_user_(per_user) {}

  // One open stream; gives its slot back when it goes.
  class Ticket {
   public:
    Ticket() = default;
    Ticket(StreamSlots* slots, std::string user) : slots_(slots), user_(std::move(user)) {}
    Ticket(Ticket&& other) noexcept
        : slots_(std::exchange(other.slots_, nullptr)), user_(std::move(other.user_)) {}
    Ticket& operator=(Ticket&& other) noexcept {
      if (this != &other) {
        Reset();
        slots_ = std::exchange(other.slots_, nullptr);
        user_ = std::move(other.user_);
      }
      return *this;
    }
    ~Ticket() { Reset(); }
    bool held() const { return slots_ != nullptr; }

   private:
    void Reset() {
      if (slots_ != nullptr) slots_->Release(user_);
      slots_ = nullptr;
    }
    StreamSlots* slots_ = nullptr;
    std::string user_;
  };

  // A held ticket, or an empty one when `user` already has per_user()
  // streams open.
  Ticket TryAcquire(const std::string& user) {
    std::lock_guard lock(mutex_);
    int& open = open_[user];
    if (open >= per_user_) return Ticket();
    ++open;
    return Ticket(this, user);
  }

  int per_user() const { return per_user_; }

  int open(const std::string& user) const {
    std::lock_guard lock(mutex_);
    const auto it = open_.find(user);
    return it == open_.end() ? 0 : it->second;
  }

 private:
  void Release(const std::string& user) {
    std::lock_guard lock(mutex_);
    const auto it = open_.find(user);
    if (it != open_.end() && --it->second <= 0) open_.erase(it);
  }

  const int per_user_;
  mutable std::mutex mutex_;
  std::map<std::string, int> open_;  // guarded by mutex_; users with a stream open
};

}  // namespace pba
