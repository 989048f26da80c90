// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <mutex>
#include <vector>

#include "ubersim/events.hpp"

namespace ubersim::kernel {

/// Thread-safe FIFO of events: transports post from any thread, the simulation thread drains.
class EventQueue final : public EventSink {
 public:
  /// Queues an event (any thread).
  void Post(Event event) override {
    std::lock_guard lock(mutex_);
    pending_.push_back(std::move(event));
  }
  /// Takes every queued event, oldest first (simulation thread).
  std::vector<Event> Drain() {
    std::vector<Event> out;
    std::lock_guard lock(mutex_);
    out.swap(pending_);
    return out;
  }

 private:
  std::mutex mutex_;
  std::vector<Event> pending_;
};

}  // namespace ubersim::kernel
