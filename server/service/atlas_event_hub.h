// AtlasEventHub: where the atlas service announces each change of a project
// as it happens, and Watch streams wait for them.
//
// A watcher subscribes to one project and gets its own queue: every event
// published for that project after Subscribe() returns is appended to it, in
// publication order. Unlike the job hub, nothing is stored for replay: a
// watcher sees what happens while it is subscribed (the READY event it sends
// first marks that moment), and the audit log holds the history.
//
// A subscriber that falls behind by more than kMaxQueued events is marked
// overrun (its queue is dropped) so a stuck client cannot grow the server's
// memory; its stream then ends with RESOURCE_EXHAUSTED and the client
// re-watches and reads the audit log for what it missed.
#pragma once

#include <chrono>
#include <condition_variable>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "pba/v1/atlas.pb.h"

namespace pba {

class AtlasEventHub {
 public:
  static constexpr size_t kMaxQueued = 10000;

  // One watcher's queue; unsubscribes when destroyed.
  class Subscription {
   public:
    ~Subscription();
    Subscription(const Subscription&) = delete;
    Subscription& operator=(const Subscription&) = delete;

    // Waits up to `timeout` for events, then moves the queued ones (possibly
    // none) into *events. False once the hub shuts down or the queue was
    // overrun (*overrun says which).
    bool Next(std::chrono::milliseconds timeout, std::vector<v1::AtlasEvent>* events,
              bool* overrun);

   private:
    friend class AtlasEventHub;
    Subscription(AtlasEventHub& hub, std::string project)
        : hub_(hub), project_(std::move(project)) {}

    AtlasEventHub& hub_;
    const std::string project_;
    std::deque<v1::AtlasEvent> queue_;  // guarded by hub_.mutex_
    bool overrun_ = false;
  };

  std::unique_ptr<Subscription> Subscribe(const std::string& project);

  // Appends `event` to the queue of every subscriber of event.project().
  void Publish(const v1::AtlasEvent& event);

  // Ends every Next() for good: streams end when the server stops.
  void Shutdown();
  bool shutting_down() const;

  // Subscribers now (for tests and logs).
  size_t subscribers() const;

 private:
  void Unsubscribe(Subscription* subscription);

  mutable std::mutex mutex_;
  std::condition_variable changed_;
  bool shutting_down_ = false;
  std::multimap<std::string, Subscription*> subscribers_;
};

}  // namespace pba
