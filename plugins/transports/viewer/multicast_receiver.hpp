// SPDX-License-Identifier: Apache-2.0
// Receives a UDP multicast group the way a team's software does: one socket bound to
// INADDR_ANY:port (shared with other programs on this machine, SO_REUSEADDR) that joined the
// group on each given interface, received on a thread of its own. The viewer listens to the
// referee with it; transport_common has senders and a unicast server, no group receiver (move
// this there when a second transport needs one).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace ubersim::viewer {

class MulticastReceiver {
 public:
  /// One datagram's bytes, valid during the call (receive thread).
  using Handler = std::function<void(std::span<const std::uint8_t> bytes)>;
  /// A datagram not handed over (too long, a receive error, the handler threw), and why.
  using DropHandler = std::function<void(const std::string& reason)>;

  struct Options {
    std::string group = "224.5.23.1";      ///< IPv4 multicast group, numeric
    std::uint16_t port = 10003;            ///< 0: the system picks one (tests)
    std::vector<std::string> interfaces = {"127.0.0.1"};  ///< addresses of the interfaces to join on
    std::size_t max_datagram = 65507;      ///< bytes; longer ones are dropped
    std::string name = "multicast receiver";  ///< for error messages
  };

  /// True for a numeric IPv4 multicast address (224.0.0.0 to 239.255.255.255).
  static bool IsIpv4Group(const std::string& address);

  /// Opens, binds and joins; throws std::runtime_error naming group, port and interface when the
  /// group is not a multicast address, the bind fails, or no interface could be joined. Joins that
  /// fail on some interfaces only are listed in JoinFailures.
  MulticastReceiver(const Options& options, Handler handler, DropHandler on_drop = {});
  /// Stops and joins.
  ~MulticastReceiver();
  MulticastReceiver(const MulticastReceiver&) = delete;
  MulticastReceiver& operator=(const MulticastReceiver&) = delete;

  /// Starts the receive thread.
  void Start();
  /// Closes the socket and joins the thread; idempotent. Never call it from a handler.
  void Stop();
  /// The bound port (the system's pick when Options::port was 0).
  std::uint16_t Port() const;
  /// Addresses of the interfaces the group was joined on.
  const std::vector<std::string>& Joined() const;
  /// "192.168.1.5: No such device" for each interface that could not join.
  const std::vector<std::string>& JoinFailures() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ubersim::viewer
