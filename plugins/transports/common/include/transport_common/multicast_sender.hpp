// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>

namespace ubersim::transport {

/// Sends datagrams to a UDP multicast group (or a unicast address) from the simulation thread.
/// Multicast goes out on a chosen interface with a TTL and loops back to this host, so receivers
/// on the same machine (and on loopback alone, with no network) see it.
class MulticastSender {
 public:
  /// Where and how to send.
  struct Options {
    std::string group = "224.5.23.2";        ///< multicast group (or unicast address), numeric
    std::uint16_t port = 10020;              ///< destination port
    std::string interface_address = "127.0.0.1";  ///< outgoing interface; "" or "0.0.0.0" = the system's choice
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
  /// "udp multicast 224.5.23.2:10020 via 127.0.0.1" (or "via the system's choice").
  std::string Describe() const;
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
