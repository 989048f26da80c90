// SPDX-License-Identifier: Apache-2.0
#include "transport_common/wire_clock.hpp"

#include <chrono>
#include <stdexcept>
#include <utility>

#include "transport_common/wire_units.hpp"

namespace ubersim::transport {

TimestampMode ParseTimestampMode(const std::string& text) {
  if (text == "unix") return TimestampMode::kUnix;
  if (text == "sim") return TimestampMode::kSim;
  throw std::invalid_argument("timestamps must be 'unix' or 'sim', not '" + text + "'");
}

double SystemUnixSeconds() {
  const auto since_epoch = std::chrono::system_clock::now().time_since_epoch();
  return std::chrono::duration<double>(since_epoch).count();
}

WireClock::WireClock(TimestampMode mode, std::function<double()> unix_now)
    : mode_(mode), unix_now_(std::move(unix_now)) {}

void WireClock::Update(std::int64_t sim_now_ns) {
  if (!anchored_ || sim_now_ns < last_now_ns_) {
    offset_ = mode_ == TimestampMode::kUnix ? unix_now_() - NsToSeconds(sim_now_ns) : 0.0;
    anchored_ = true;
  }
  last_now_ns_ = sim_now_ns;
}

double WireClock::Seconds(std::int64_t sim_ns) {
  if (!anchored_) Update(sim_ns);
  return offset_ + NsToSeconds(sim_ns);
}

}  // namespace ubersim::transport
