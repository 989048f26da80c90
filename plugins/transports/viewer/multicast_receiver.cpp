// SPDX-License-Identifier: Apache-2.0
#include <utility>  // before Boost.Asio: its 1.74 headers use std::exchange without it

#include "multicast_receiver.hpp"

#include <atomic>
#include <exception>
#include <stdexcept>
#include <thread>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/multicast.hpp>
#include <boost/asio/ip/udp.hpp>

namespace ubersim::viewer {

namespace asio = boost::asio;
using asio::ip::udp;

struct MulticastReceiver::Impl {
  Options options;
  Handler handler;
  DropHandler on_drop;
  asio::io_context io;
  udp::socket socket{io};
  std::vector<std::uint8_t> buffer;
  udp::endpoint sender;
  std::vector<std::string> joined;
  std::vector<std::string> join_failures;
  std::thread thread;
  std::atomic<bool> running{false};

  void Drop(const std::string& reason) {
    if (!on_drop) return;
    try {
      on_drop(reason);
    } catch (const std::exception&) {
      // A reporting callback must not end the receive loop.
    }
  }

  void Receive() {
    socket.async_receive_from(asio::buffer(buffer), sender, [this](const boost::system::error_code& ec, std::size_t n) {
      if (ec == asio::error::operation_aborted || !socket.is_open()) return;
      if (ec) {
        Drop("receive failed: " + ec.message());
      } else if (n > options.max_datagram) {
        // The buffer is one byte longer than allowed, so a longer datagram shows as n > max.
        Drop("datagram longer than " + std::to_string(options.max_datagram) + " bytes");
      } else {
        try {
          handler(std::span<const std::uint8_t>(buffer.data(), n));
        } catch (const std::exception& e) {
          Drop(std::string("handler threw: ") + e.what());
        }
      }
      Receive();
    });
  }
};

bool MulticastReceiver::IsIpv4Group(const std::string& address) {
  boost::system::error_code ec;
  const asio::ip::address a = asio::ip::make_address(address, ec);
  return !ec && a.is_v4() && a.is_multicast();
}

MulticastReceiver::MulticastReceiver(const Options& options, Handler handler, DropHandler on_drop)
    : impl_(std::make_unique<Impl>()) {
  if (!handler) throw std::invalid_argument(options.name + ": no datagram handler");
  impl_->options = options;
  impl_->handler = std::move(handler);
  impl_->on_drop = std::move(on_drop);
  impl_->buffer.resize(options.max_datagram + 1);
  const std::string where = options.group + ":" + std::to_string(options.port);
  if (!IsIpv4Group(options.group)) {
    throw std::runtime_error(options.name + ": '" + options.group +
                             "' is not an IPv4 multicast group (224.0.0.0 to 239.255.255.255)");
  }
  const asio::ip::address_v4 group = asio::ip::make_address_v4(options.group);
  boost::system::error_code ec;
  udp::socket& s = impl_->socket;
  s.open(udp::v4(), ec);
  // Shared with the team's software on this machine, which listens on the same port.
  if (!ec) s.set_option(asio::socket_base::reuse_address(true), ec);
  if (!ec) s.bind(udp::endpoint(asio::ip::address_v4::any(), options.port), ec);
  if (ec) {
    throw std::runtime_error(options.name + ": cannot bind UDP 0.0.0.0:" + std::to_string(options.port) + ": " +
                             ec.message());
  }
  for (const std::string& address : options.interfaces) {
    const asio::ip::address iface = asio::ip::make_address(address, ec);
    if (ec || !iface.is_v4()) {
      impl_->join_failures.push_back(address + ": not a numeric IPv4 address");
      continue;
    }
    s.set_option(asio::ip::multicast::join_group(group, iface.to_v4()), ec);
    if (ec) impl_->join_failures.push_back(address + ": " + ec.message());
    else impl_->joined.push_back(address);
  }
  if (impl_->joined.empty()) {
    std::string why;
    for (const std::string& f : impl_->join_failures) why += (why.empty() ? "" : "; ") + f;
    throw std::runtime_error(options.name + ": cannot join " + where + " on any interface (" +
                             (why.empty() ? std::string("none given") : why) + ")");
  }
}

MulticastReceiver::~MulticastReceiver() { Stop(); }

void MulticastReceiver::Start() {
  if (impl_->running.exchange(true)) return;
  impl_->Receive();
  impl_->thread = std::thread([impl = impl_.get()] {
    try {
      impl->io.run();
    } catch (const std::exception& e) {
      impl->Drop(std::string("receive thread stopped: ") + e.what());
    }
  });
}

void MulticastReceiver::Stop() {
  if (impl_->thread.joinable() && impl_->thread.get_id() == std::this_thread::get_id()) {
    throw std::logic_error(impl_->options.name + ": Stop called from its own receive thread");
  }
  impl_->running = false;
  impl_->io.stop();
  if (impl_->thread.joinable()) impl_->thread.join();
  boost::system::error_code ignored;
  impl_->socket.close(ignored);  // leaves the groups
}

std::uint16_t MulticastReceiver::Port() const {
  boost::system::error_code ec;
  const udp::endpoint e = impl_->socket.local_endpoint(ec);
  return ec ? 0 : e.port();
}

const std::vector<std::string>& MulticastReceiver::Joined() const { return impl_->joined; }

const std::vector<std::string>& MulticastReceiver::JoinFailures() const { return impl_->join_failures; }

}  // namespace ubersim::viewer
