// SPDX-License-Identifier: Apache-2.0
#include "udp_port.hpp"

#include <stdexcept>

#include <boost/asio/buffer.hpp>

namespace ubersim::ssl_simulation {

namespace asio = boost::asio;
using asio::ip::udp;

UdpPort::UdpPort(asio::io_context& io, const std::string& address, std::uint16_t port, Handler handler)
    : socket_(io), handler_(std::move(handler)), port_(port) {
  boost::system::error_code ec;
  const asio::ip::address ip = asio::ip::make_address(address, ec);
  if (ec) throw std::runtime_error("'" + address + "' is not an IP address");
  const udp::endpoint local(ip, port);
  socket_.open(local.protocol(), ec);
  if (!ec) socket_.bind(local, ec);
  if (ec) {
    throw std::runtime_error("cannot bind udp " + address + ":" + std::to_string(port) + ": " + ec.message());
  }
}

void UdpPort::Receive() {
  socket_.async_receive_from(asio::buffer(buffer_), sender_, [this](boost::system::error_code ec, std::size_t n) {
    // Closed: stop. Anything else (an ICMP refusal from an earlier reply) affects one datagram only.
    if (ec == asio::error::operation_aborted || ec == asio::error::bad_descriptor) return;
    if (!ec) {
      const std::string reply = handler_(std::string_view(buffer_.data(), n));
      // Always answered, even with zero bytes (an empty response message). Best effort, as UDP
      // is: a full socket buffer or a vanished client loses this reply only.
      boost::system::error_code send_ec;
      socket_.send_to(asio::buffer(reply), sender_, 0, send_ec);
    }
    Receive();
  });
}

}  // namespace ubersim::ssl_simulation
