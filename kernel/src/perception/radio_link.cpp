// SPDX-License-Identifier: Apache-2.0
#include "perception/radio_link.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace ubersim::kernel {
namespace {

std::int64_t Ns(double seconds) { return static_cast<std::int64_t>(std::llround(seconds * 1e9)); }

// The radio's own random stream from the world's seed (the vision's is another).
constexpr std::uint64_t kRadioStream = 0x524144494f000002ULL;

}  // namespace

RadioLink::RadioLink(RadioModel model, std::uint64_t seed)
    : model_(std::move(model)), seed_(seed), latency_ns_(Ns(model_.latency)) {
  Reset();
}

void RadioLink::Reset(std::uint64_t seed) {
  seed_ = seed;
  Reset();
}

void RadioLink::Reset() {
  queue_.clear();
  rng_.seed(seed_ ^ kRadioStream);
}

void RadioLink::Configure(const RadioModel& model) {
  model_ = model;
  latency_ns_ = Ns(model_.latency);
}

bool RadioLink::Send(CommandEvent&& command, std::int64_t now_ns) {
  if (model_.loss > 0 && std::uniform_real_distribution<double>(0.0, 1.0)(rng_) < model_.loss) return false;
  queue_.emplace_back(now_ns + latency_ns_, std::move(command));
  return true;
}

RadioState RadioLink::SaveState() const {
  RadioState s;
  s.model = model_;
  s.queue.assign(queue_.begin(), queue_.end());
  std::ostringstream rng;
  rng << rng_;
  s.rng = rng.str();
  return s;
}

void RadioLink::RestoreState(const RadioState& s) {
  std::mt19937_64 rng;
  std::istringstream in(s.rng);
  in >> rng;
  if (!in) throw std::invalid_argument("the saved radio loss generator is unreadable");
  RadioModel m = model_;
  m.latency = s.model.latency;
  m.loss = s.model.loss;
  m.response_loss = s.model.response_loss;
  Configure(m);
  queue_.assign(s.queue.begin(), s.queue.end());
  rng_ = rng;
}

std::vector<bool> RadioLink::ResponsesLost(std::size_t robots) {
  std::vector<bool> lost(robots, false);
  if (model_.response_loss <= 0) return lost;
  std::uniform_real_distribution<double> chance(0.0, 1.0);
  for (std::size_t i = 0; i < robots; ++i) lost[i] = chance(rng_) < model_.response_loss;
  return lost;
}

std::vector<CommandEvent> RadioLink::Deliver(std::int64_t now_ns) {
  std::vector<CommandEvent> out;
  while (NextDue(now_ns)) {
    out.push_back(std::move(queue_.front().second));
    PopDue();
  }
  return out;
}

}  // namespace ubersim::kernel
