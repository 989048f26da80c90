// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>
#include <functional>
#include <string>

namespace ubersim::transport {

/// What the timestamps a transport sends count: Unix time (what real ssl-vision sends and most
/// team software expects) or plain simulated time (what grSim sends).
enum class TimestampMode { kUnix, kSim };

/// Parses the `timestamps:` parameter ("unix" or "sim"); throws std::invalid_argument otherwise.
TimestampMode ParseTimestampMode(const std::string& text);

/// Seconds since the Unix epoch, from the system clock.
double SystemUnixSeconds();

/// Turns simulated time into the seconds sent on the wire. In Unix mode the clock is anchored once,
/// offset = Unix time now − sim time now, and every stamp is offset + sim time, so stamps keep the
/// simulation's spacing exactly (also when it runs faster than real time). Not thread-safe: one
/// owner thread (the simulation's).
class WireClock {
 public:
  /// `unix_now` is injectable for tests.
  explicit WireClock(TimestampMode mode, std::function<double()> unix_now = SystemUnixSeconds);
  /// Tells the clock the simulation's current time: the first call anchors it; time going
  /// backwards (a world reset) anchors it again.
  void Update(std::int64_t sim_now_ns);
  /// The wire timestamp, s, of simulated time `sim_ns` (anchors at `sim_ns` if never updated).
  double Seconds(std::int64_t sim_ns);
  /// The mode.
  TimestampMode Mode() const { return mode_; }

 private:
  TimestampMode mode_;
  std::function<double()> unix_now_;
  bool anchored_ = false;
  double offset_ = 0.0;
  std::int64_t last_now_ns_ = 0;
};

}  // namespace ubersim::transport
