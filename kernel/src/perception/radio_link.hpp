// SPDX-License-Identifier: Apache-2.0
// The simulated radio between the teams' software and the robots: latency and loss.
#pragma once

#include <cstdint>
#include <deque>
#include <random>
#include <utility>
#include <vector>

#include "ubersim/events.hpp"
#include "ubersim/kernel/model.hpp"
#include "ubersim/kernel/snapshot.hpp"

namespace ubersim::kernel {

/// Delays robot commands by the radio latency and loses some; deterministic for a seed.
class RadioLink {
 public:
  RadioLink(RadioModel model, std::uint64_t seed);
  /// A command arriving at `now_ns`: false when the radio loses it, else it is queued.
  bool Send(CommandEvent&& command, std::int64_t now_ns);
  /// Commands due by `now_ns`, in arrival order.
  std::vector<CommandEvent> Deliver(std::int64_t now_ns);
  /// The oldest queued command if it is due by `now_ns` (it stays queued until PopDue), else
  /// null: Deliver without moving each command into a new vector.
  const CommandEvent* NextDue(std::int64_t now_ns) const {
    return !queue_.empty() && queue_.front().first <= now_ns ? &queue_.front().second : nullptr;
  }
  /// Drops the command NextDue returned.
  void PopDue() { queue_.pop_front(); }
  /// Forgets queued commands (world reset).
  void Reset();
  /// Reset with another seed (the world reset with a new seed).
  void Reset(std::uint64_t seed);
  /// Whether each of `robots` robots' feedback is lost this step (drawn only when some is).
  std::vector<bool> ResponsesLost(std::size_t robots);
  /// Changes latency and loss while running.
  void Configure(const RadioModel& model);
  /// The configuration.
  const RadioModel& model() const { return model_; }
  /// Everything it carries between steps.
  RadioState SaveState() const;
  /// Puts back what SaveState returned; throws std::invalid_argument when it is unreadable.
  void RestoreState(const RadioState& state);

 private:
  RadioModel model_;
  std::uint64_t seed_;
  std::int64_t latency_ns_;
  std::deque<std::pair<std::int64_t, CommandEvent>> queue_;
  std::mt19937_64 rng_;
};

}  // namespace ubersim::kernel
