// SPDX-License-Identifier: Apache-2.0
// Events into a world: the thread-safe queue transports and in-process clients post commands,
// teleports, clock and realism events to; the world drains it at the start of each step.
#pragma once

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <vector>

#include "ubersim/events.hpp"

namespace ubersim::kernel {

/// Thread-safe FIFO of events: transports post from any thread, the simulation thread drains.
class EventQueue final : public EventSink {
 public:
  /// Queues an event (any thread).
  void Post(Event event) override {
    {
      std::lock_guard lock(mutex_);
      pending_.push_back(std::move(event));
    }
    posted_.notify_all();
  }
  /// Waits until an event is queued or `timeout` passes (a paused world idles here, so a
  /// client's step request is served at once instead of after a polling interval).
  void WaitForEvent(std::chrono::milliseconds timeout) {
    std::unique_lock lock(mutex_);
    posted_.wait_for(lock, timeout, [this] { return !pending_.empty(); });
  }
  /// Takes every queued event, oldest first (simulation thread).
  std::vector<Event> Drain() {
    std::vector<Event> out;
    Drain(out);
    return out;
  }
  /// The same into `out` (its events dropped first), whose storage the queue keeps for the next
  /// events: a caller draining every step into one vector allocates nothing once both have grown.
  void Drain(std::vector<Event>& out) {
    out.clear();
    std::lock_guard lock(mutex_);
    out.swap(pending_);
  }

 private:
  std::mutex mutex_;
  std::condition_variable posted_;
  std::vector<Event> pending_;
};

}  // namespace ubersim::kernel
