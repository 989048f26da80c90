// SPDX-License-Identifier: Apache-2.0
// What runs beside a world for a match: the built-in referee (its Referee messages on
// 224.5.23.1:10003 and what it asks of the field), tracked output on 224.5.23.2:10010, and a
// recorder of every message in the league's log format. Called between steps on the world's
// thread (RunOptions::between_steps, or a loop of one's own); never touches the world otherwise.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include <ubersim/log.hpp>

#include "referee_engine.hpp"
#include "ubersim/kernel/world.hpp"

namespace ubersim::match {

/// The league's message types in a log file (ssl-match-protocols.md §4.2).
enum class WireMessage : std::int32_t { kReferee = 3, kVision = 4, kTracker = 5 };

/// Gets every message the session sends or the world's cameras produce, with its Unix time
/// stamp, ns (what a log recorder would have received then).
using MessageRecorder = std::function<void(std::int64_t unix_ns, WireMessage type, const std::string& bytes)>;

/// How a session runs.
struct MatchOptions {
  std::optional<RefereeConfig> referee;  ///< the referee's rules; none: no referee
  /// "HOST:PORT" of a game controller in CI mode: the referee is its autoreferee and publishes its
  /// Referee messages; empty: the referee is the built-in game controller.
  std::string game_controller;
  double ci_rate = 100.0;                ///< CiInputs per simulated second
  bool tracker = false;                  ///< publish TrackerWrapperPackets
  bool tracker_noise = false;            ///< tracked positions carry the perception pipeline's noise (seeded by the world)
  double referee_rate = 40.0;            ///< Referee messages per simulated second, besides one per command
  double tracker_rate = 60.0;            ///< tracked frames per simulated second
  std::string referee_address = "224.5.23.1";  ///< referee group
  std::uint16_t referee_port = 10003;          ///< referee port
  std::string tracker_address = "224.5.23.2";  ///< tracker group
  std::uint16_t tracker_port = 10010;          ///< tracker port
  bool network = true;           ///< send on the network (false: only record / observe)
  bool local_only = false;       ///< loopback only
  bool unix_timestamps = true;   ///< time stamps in Unix time (else plain simulated time)
  /// With unix_timestamps: Unix ns minus simulated ns, when the caller stamps records of its own on
  /// the same clock; unset: anchored at the first stamp.
  std::optional<std::int64_t> unix_offset_ns;
  MessageRecorder recorder;      ///< may be empty
};

/// The referee, tracker and recorder of one world.
class MatchSession {
 public:
  /// Starts the senders (throws std::runtime_error naming the group when a socket fails) and, when
  /// recording, takes the world's vision observer.
  MatchSession(kernel::World& world, MatchOptions options, Log& log);
  ~MatchSession();
  MatchSession(const MatchSession&) = delete;
  MatchSession& operator=(const MatchSession&) = delete;

  /// Between steps: when the world has stepped since the last call, watches it, publishes, and
  /// posts what the referee asks of the field as events for the next step.
  void AfterStep();
  /// The built-in referee, or null.
  const RefereeEngine* referee() const { return referee_.get(); }
  /// The game controller link's description, or "".
  std::string GameController() const;
  /// "referee udp multicast 224.5.23.1:10003 via …", one line per sender.
  std::vector<std::string> Endpoints() const;

 private:
  struct Senders;
  void Send(WireMessage type, const std::string& bytes, std::int64_t sim_ns);
  void Carry(const std::vector<FieldRequest>& requests, const WorldSnapshot& truth);
  void ExchangeWithGameController(const WorldSnapshot& truth, std::int64_t now);
  std::int64_t UnixOffset();

  kernel::World& world_;
  MatchOptions options_;
  Log& log_;
  std::unique_ptr<RefereeEngine> referee_;
  std::unique_ptr<Senders> senders_;
  std::unique_ptr<class GameControllerLink> link_;
  std::int64_t next_ci_ns_ = 0;
  std::uint32_t ci_frame_ = 0;
  bool ci_started_ = false;
  std::int64_t last_step_ = -1;
  std::int64_t next_referee_ns_ = 0;
  std::int64_t next_tracker_ns_ = 0;
  std::uint32_t tracker_frame_ = 0;
  std::string tracker_uuid_;
  std::mt19937_64 tracker_rng_;
  std::optional<std::int64_t> unix_offset_ns_;
};

}  // namespace ubersim::match
