// SPDX-License-Identifier: Apache-2.0
#include "transport_common/multicast_sender.hpp"

#include <atomic>
#include <mutex>
#include <stdexcept>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/multicast.hpp>
#include <boost/asio/ip/udp.hpp>
#include <boost/asio/ip/unicast.hpp>

#include "transport_common/udp_server.hpp"

namespace ubersim::transport {

namespace asio = boost::asio;
using asio::ip::udp;

struct MulticastSender::Impl {
  Options options;
  asio::io_context io;  // only to own the socket; sends are synchronous
  udp::socket socket{io};
  UdpEndpoint destination;
  std::string description;
  mutable std::mutex mutex;
  std::string last_error;
  std::atomic<std::uint64_t> sent{0};
  std::atomic<std::uint64_t> failed{0};
};

MulticastSender::MulticastSender(const Options& options) : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  s.options = options;
  if (options.group.empty()) throw std::runtime_error(options.name + ": no destination address");
  s.destination = MakeEndpoint(options.group, options.port, options.name);
  const bool any_interface = options.interface_address.empty() || options.interface_address == "0.0.0.0";
  const bool multicast = s.destination.address().is_multicast();
  s.description = std::string(multicast ? "udp multicast " : "udp ") + ToString(s.destination);
  if (multicast) {
    s.description += " via " + (any_interface ? std::string("the system's choice") : options.interface_address);
  }
  if (options.ttl < 0 || options.ttl > 255) {
    throw std::runtime_error(options.name + ": TTL " + std::to_string(options.ttl) + " is outside 0..255");
  }

  boost::system::error_code ec;
  const auto fail = [&](const std::string& step) {
    throw std::runtime_error(options.name + ": cannot set up " + s.description + ": " + step + ": " + ec.message());
  };
  s.socket.open(s.destination.protocol(), ec);
  if (ec) fail("open");
  if (multicast) {
    s.socket.set_option(asio::ip::multicast::hops(options.ttl), ec);
    if (ec) fail("TTL");
    s.socket.set_option(asio::ip::multicast::enable_loopback(options.loopback), ec);
    if (ec) fail("loopback");
    if (!any_interface) {
      const UdpEndpoint iface = MakeEndpoint(options.interface_address, 0, options.name + " interface");
      if (!iface.address().is_v4() || !s.destination.address().is_v4()) {
        ec = asio::error::address_family_not_supported;
        fail("interface " + options.interface_address);
      }
      s.socket.set_option(asio::ip::multicast::outbound_interface(iface.address().to_v4()), ec);
      if (ec) fail("interface " + options.interface_address);
    }
  } else {
    s.socket.set_option(asio::ip::unicast::hops(options.ttl), ec);
    if (ec) fail("TTL");
  }
}

MulticastSender::~MulticastSender() {
  boost::system::error_code ignored;
  impl_->socket.close(ignored);
}

bool MulticastSender::Send(std::span<const std::uint8_t> bytes) {
  std::lock_guard lock(impl_->mutex);
  boost::system::error_code ec;
  impl_->socket.send_to(asio::buffer(bytes.data(), bytes.size()), impl_->destination, 0, ec);
  if (ec) {
    ++impl_->failed;
    impl_->last_error = ec.message();
    return false;
  }
  ++impl_->sent;
  return true;
}

std::string MulticastSender::Describe() const { return impl_->description; }

std::string MulticastSender::LastError() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->last_error;
}

std::uint64_t MulticastSender::Sent() const { return impl_->sent; }
std::uint64_t MulticastSender::Failed() const { return impl_->failed; }

}  // namespace ubersim::transport
