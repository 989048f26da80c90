// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace ubersim::transport {

/// Sends datagrams to a UDP multicast group (or a unicast address) from the simulation thread.
/// Multicast goes out on one or more interfaces with a TTL and loops back to this host, so
/// receivers on the same machine see it whichever interface they joined on. By default ("auto")
/// that is loopback plus the interface of the default route, followed as it changes. Each local
/// receiver gets each datagram once: Linux hands a multicast datagram looped back on an
/// interface to every local socket bound to the port (IP_MULTICAST_ALL), so the loopback copy
/// is left out while a local socket has joined the group on another interface sent on.
class MulticastSender {
 public:
  /// Where and how to send.
  struct Options {
    std::string group = "224.5.23.2";        ///< multicast group (or unicast address), numeric
    std::uint16_t port = 10020;              ///< destination port
    /// Outgoing interfaces by address: "auto" (loopback plus the default route's interface),
    /// numeric addresses, "0.0.0.0" (the system's choice: needs a multicast route).
    std::vector<std::string> interfaces = {"auto"};
    bool local_only = false;                 ///< loopback only, whatever `interfaces` says
    int ttl = 1;                             ///< hops; 1 stays on the local network
    bool loopback = true;                    ///< deliver to receivers on this host too
    std::string name = "multicast sender";   ///< for error messages
  };

  /// Opens the socket and sets the options; throws std::runtime_error naming group, port and
  /// interface when that fails.
  explicit MulticastSender(const Options& options);
  ~MulticastSender();
  MulticastSender(const MulticastSender&) = delete;
  MulticastSender& operator=(const MulticastSender&) = delete;

  /// Sends one datagram; thread-safe. False (with the error in LastError) when the system
  /// refused it, e.g. no route to the group.
  bool Send(std::span<const std::uint8_t> bytes);
  /// "udp multicast 224.5.23.2:10020 via lo 127.0.0.1 and eth0 192.168.1.5".
  std::string Describe() const;
  /// The interface addresses multicast goes out on now (one entry for unicast: "").
  std::vector<std::string> Interfaces() const;
  /// The system's message for the last failed Send, or "".
  std::string LastError() const;
  /// Datagrams sent / refused since construction.
  std::uint64_t Sent() const;
  std::uint64_t Failed() const;  ///< refused sends

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ubersim::transport
