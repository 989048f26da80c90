// SPDX-License-Identifier: Apache-2.0
// One bound UDP port that answers every datagram to its sender (the simulation protocol's
// request/response ports). Runs on the caller's io_context thread.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/udp.hpp>

namespace ubersim::ssl_simulation {

/// Receives datagrams and sends the handler's answer back to the datagram's source address:port.
class UdpPort {
 public:
  /// Turns one datagram into the reply bytes (sent even when empty: an empty message).
  using Handler = std::function<std::string(std::string_view datagram)>;

  /// Binds address:port; throws std::runtime_error naming both when that fails.
  UdpPort(boost::asio::io_context& io, const std::string& address, std::uint16_t port, Handler handler);
  /// Starts receiving (call before running the io_context).
  void Start() { Receive(); }
  /// The bound port.
  std::uint16_t Port() const { return port_; }

 private:
  void Receive();

  boost::asio::ip::udp::socket socket_;
  boost::asio::ip::udp::endpoint sender_;
  // Larger than any UDP payload (65507 bytes), so size limits are ours, not truncation's.
  std::array<char, 65536> buffer_{};
  Handler handler_;
  std::uint16_t port_;
};

}  // namespace ubersim::ssl_simulation
