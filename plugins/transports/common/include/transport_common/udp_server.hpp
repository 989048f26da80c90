// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <boost/asio/ip/udp.hpp>

namespace ubersim::transport {

/// An IPv4/IPv6 UDP address and port.
using UdpEndpoint = boost::asio::ip::udp::endpoint;

/// "127.0.0.1:20011".
std::string ToString(const UdpEndpoint& endpoint);

/// Parses a numeric address ("127.0.0.1", "::1"; "" and "0.0.0.0" mean any) and a port;
/// throws std::runtime_error naming `what` and the bad text.
UdpEndpoint MakeEndpoint(const std::string& address, std::uint16_t port, const std::string& what);

/// Why a UdpServer dropped a datagram (or a reply): the kind, for a transport that answers some
/// drops (e.g. an oversized request with an error reply), and the text, for its log.
struct DropReason {
  enum class Kind {
    kOversized,      ///< longer than Options::max_datagram; the sender is known, so it can be told
    kReceiveFailed,  ///< the socket reported an error (e.g. an ICMP refusal of an earlier reply)
    kHandlerThrew,   ///< the datagram handler threw
    kReplyFailed,    ///< Reply could not send; the endpoint is the destination
    kStopped,        ///< the receive thread ended on an exception
  };
  Kind kind;
  std::string text;  ///< "datagram longer than 8192 bytes"
  /// Lets a handler that only logs take the reason as text.
  operator const std::string&() const { return text; }
};

/// UDP sockets bound to one port on one or more addresses, received on one thread of their own
/// (a Boost.Asio io_context), each whole datagram handed to a handler with its sender. A reply
/// leaves from the address its request came to. Thread-safe Reply. Datagrams longer than
/// `max_datagram` are dropped and reported, never handed over cut short.
class UdpServer {
 public:
  /// What arrived: the bytes (valid during the call) and who sent them.
  using Handler = std::function<void(std::span<const std::uint8_t> bytes, const UdpEndpoint& sender)>;
  /// Why a datagram was not handed over, and from whom; runs on the receive thread (except for a
  /// failed Reply, on the caller's), so it may Reply to the sender.
  using DropHandler = std::function<void(const DropReason& reason, const UdpEndpoint& sender)>;

  /// Where to listen and how large a datagram may be.
  struct Options {
    /// Numeric addresses to bind, each with its own socket; "" or "0.0.0.0" = every interface.
    std::vector<std::string> addresses = {"127.0.0.1"};
    std::uint16_t port = 0;              ///< 0 = the system picks one (see LocalEndpoint)
    std::size_t max_datagram = 65507;    ///< bytes; longer ones are dropped
    std::string name = "udp server";     ///< for error messages
  };

  /// Binds the sockets (throws std::runtime_error naming address and port when it cannot, e.g.
  /// "grsim: cannot bind UDP 127.0.0.1:20011: Address already in use"); does not start receiving.
  UdpServer(const Options& options, Handler handler, DropHandler on_drop = {});
  /// Stops and joins.
  ~UdpServer();
  UdpServer(const UdpServer&) = delete;
  UdpServer& operator=(const UdpServer&) = delete;

  /// Starts the receive thread; handlers run on it, one datagram at a time.
  void Start();
  /// Closes the socket and joins the thread; idempotent. Never call it from a handler.
  void Stop();
  /// Sends one datagram to `to` from the socket that last heard from its address (inside a
  /// handler: the one that received the datagram); thread-safe, never blocks on the network.
  /// False when it could not be queued or sent (the reason goes to the drop handler).
  bool Reply(const UdpEndpoint& to, std::span<const std::uint8_t> bytes);
  /// The first bound address and port (the real port when Options::port was 0).
  UdpEndpoint LocalEndpoint() const;
  /// Every bound address and port.
  std::vector<UdpEndpoint> LocalEndpoints() const;

  /// Datagrams handed to the handler / dropped since construction (any thread).
  std::uint64_t Received() const;
  std::uint64_t Dropped() const;  ///< oversized or failed receives and failed replies

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ubersim::transport
