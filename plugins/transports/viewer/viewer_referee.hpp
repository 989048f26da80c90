// SPDX-License-Identifier: Apache-2.0
// The match on the page: the league's Referee message (what the game controller or `ubersim run
// --referee builtin` publishes) as the viewer's "referee" JSON message in SI units, and the relay
// that decides which of them reach the browsers. No sockets here (docs/viewer.md has the format).
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>

class GameEvent;
class Referee;

namespace ubersim::viewer {

/// The "referee" message: stage, command, times in s, designated position in m (or null), both
/// teams, the last game event and the status message. The packet's time stamp is left out, so an
/// unchanged match state encodes to the same text. `earlier_event` is shown as the last game event
/// when `referee` carries none (the game controller clears its list at every running command);
/// its "current" is then false.
std::string EncodeReferee(const Referee& referee, const GameEvent* earlier_event = nullptr);

/// Parses each datagram as a Referee message and hands its JSON on when the match state changed,
/// at most once per `min_interval` (the game controller sends 40 a second, the page needs ~10),
/// the newest one always last: one held back goes out at the next datagram or Tick after the
/// interval. Thread-safe: datagrams come on the receive thread, ticks on the server's.
class RefereeRelay {
 public:
  using Clock = std::chrono::steady_clock;
  /// Hands a message to the browsers; called with the relay's lock held, so it must not block
  /// (ViewerServer::Broadcast only posts) and must not call back into the relay.
  using Send = std::function<void(std::shared_ptr<const std::string> json)>;

  RefereeRelay(Clock::duration min_interval, Send send);
  ~RefereeRelay();
  RefereeRelay(const RefereeRelay&) = delete;
  RefereeRelay& operator=(const RefereeRelay&) = delete;

  /// One datagram. False (nothing changes) when it is not a complete Referee message.
  bool OnDatagram(std::span<const std::uint8_t> bytes, Clock::time_point now);
  /// Sends a held-back message once its time has come.
  void Tick(Clock::time_point now);
  /// The last message sent, for a page that connects now; null before the first.
  std::shared_ptr<const std::string> Latest() const;
  /// When the last Referee message arrived (nullopt before the first).
  std::optional<Clock::time_point> LastReceived() const;
  /// Referee messages parsed since construction.
  std::uint64_t Received() const;

 private:
  void SendLocked(Clock::time_point now);

  struct Messages;  // the protobuf messages (defined in viewer_referee.cpp)
  Clock::duration min_interval_;
  Send send_;
  mutable std::mutex mutex_;
  std::unique_ptr<Messages> messages_;
  bool pending_ = false;  // messages_->latest not yet encoded and offered
  Clock::time_point next_send_{};
  std::optional<Clock::time_point> last_received_;
  std::uint64_t received_ = 0;
  std::shared_ptr<const std::string> sent_;
};

}  // namespace ubersim::viewer
