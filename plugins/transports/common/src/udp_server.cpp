// SPDX-License-Identifier: Apache-2.0
#include "transport_common/udp_server.hpp"

#include <atomic>
#include <exception>
#include <stdexcept>
#include <thread>
#include <utility>
#include <vector>

#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>

namespace ubersim::transport {

namespace asio = boost::asio;
using asio::ip::udp;

std::string ToString(const UdpEndpoint& endpoint) {
  const std::string address = endpoint.address().to_string();
  const std::string port = std::to_string(endpoint.port());
  return endpoint.address().is_v6() ? "[" + address + "]:" + port : address + ":" + port;
}

UdpEndpoint MakeEndpoint(const std::string& address, std::uint16_t port, const std::string& what) {
  if (address.empty() || address == "0.0.0.0") return UdpEndpoint(asio::ip::address_v4::any(), port);
  boost::system::error_code ec;
  const asio::ip::address parsed = asio::ip::make_address(address, ec);
  if (ec) {
    throw std::runtime_error(what + ": '" + address + "' is not a numeric IP address (" + ec.message() + ")");
  }
  return UdpEndpoint(parsed, port);
}

struct UdpServer::Impl {
  Options options;
  Handler handler;
  DropHandler on_drop;
  asio::io_context io;
  udp::socket socket{io};
  std::vector<std::uint8_t> buffer;
  UdpEndpoint sender;
  std::thread thread;
  std::atomic<bool> running{false};
  std::atomic<std::uint64_t> received{0};
  std::atomic<std::uint64_t> dropped{0};

  void Drop(DropReason::Kind kind, std::string text, const UdpEndpoint& from) {
    ++dropped;
    if (!on_drop) return;
    try {
      on_drop(DropReason{kind, std::move(text)}, from);
    } catch (const std::exception&) {
      // A reporting callback must not end the receive loop.
    }
  }

  void Receive() {
    socket.async_receive_from(asio::buffer(buffer), sender, [this](const boost::system::error_code& ec, std::size_t n) {
      if (ec == asio::error::operation_aborted || !socket.is_open()) return;
      if (ec) {
        // E.g. an ICMP "port unreachable" after a reply to a closed port: report, keep serving.
        Drop(DropReason::Kind::kReceiveFailed, "receive failed: " + ec.message(), sender);
      } else if (n > options.max_datagram) {
        // The buffer is one byte longer than allowed, so a longer datagram shows as n > max.
        Drop(DropReason::Kind::kOversized, "datagram longer than " + std::to_string(options.max_datagram) + " bytes",
             sender);
      } else {
        ++received;
        try {
          handler(std::span<const std::uint8_t>(buffer.data(), n), sender);
        } catch (const std::exception& e) {
          Drop(DropReason::Kind::kHandlerThrew, std::string("handler threw: ") + e.what(), sender);
        }
      }
      Receive();
    });
  }

  bool SendNow(const UdpEndpoint& to, std::span<const std::uint8_t> bytes) {
    boost::system::error_code ec;
    socket.send_to(asio::buffer(bytes.data(), bytes.size()), to, 0, ec);
    if (ec) {
      Drop(DropReason::Kind::kReplyFailed, "reply to " + ToString(to) + " failed: " + ec.message(), to);
      return false;
    }
    return true;
  }
};

UdpServer::UdpServer(const Options& options, Handler handler, DropHandler on_drop)
    : impl_(std::make_unique<Impl>()) {
  if (!handler) throw std::invalid_argument(options.name + ": no datagram handler");
  if (options.max_datagram == 0) throw std::invalid_argument(options.name + ": max_datagram must be > 0");
  impl_->options = options;
  impl_->handler = std::move(handler);
  impl_->on_drop = std::move(on_drop);
  impl_->buffer.resize(options.max_datagram + 1);
  const UdpEndpoint endpoint = MakeEndpoint(options.address, options.port, options.name);
  boost::system::error_code ec;
  impl_->socket.open(endpoint.protocol(), ec);
  if (!ec) impl_->socket.bind(endpoint, ec);
  if (ec) {
    throw std::runtime_error(options.name + ": cannot bind UDP " + ToString(endpoint) + ": " + ec.message());
  }
}

UdpServer::~UdpServer() { Stop(); }

void UdpServer::Start() {
  if (impl_->running.exchange(true)) return;
  impl_->Receive();
  impl_->thread = std::thread([impl = impl_.get()] {
    try {
      impl->io.run();
    } catch (const std::exception& e) {
      impl->Drop(DropReason::Kind::kStopped, std::string("receive thread stopped: ") + e.what(), UdpEndpoint());
    }
  });
}

void UdpServer::Stop() {
  if (impl_->thread.joinable() && impl_->thread.get_id() == std::this_thread::get_id()) {
    throw std::logic_error(impl_->options.name + ": Stop called from its own receive thread");
  }
  impl_->running = false;
  impl_->io.stop();
  if (impl_->thread.joinable()) impl_->thread.join();
  boost::system::error_code ignored;
  impl_->socket.close(ignored);
}

bool UdpServer::Reply(const UdpEndpoint& to, std::span<const std::uint8_t> bytes) {
  if (!impl_->socket.is_open() || impl_->io.stopped()) return false;
  if (impl_->io.get_executor().running_in_this_thread()) return impl_->SendNow(to, bytes);
  // From another thread: hand a copy to the receive thread, which owns the socket.
  auto copy = std::make_shared<std::vector<std::uint8_t>>(bytes.begin(), bytes.end());
  asio::post(impl_->io, [impl = impl_.get(), to, copy] { impl->SendNow(to, *copy); });
  return true;
}

UdpEndpoint UdpServer::LocalEndpoint() const {
  boost::system::error_code ec;
  const UdpEndpoint e = impl_->socket.local_endpoint(ec);
  return ec ? UdpEndpoint() : e;
}

std::uint64_t UdpServer::Received() const { return impl_->received; }
std::uint64_t UdpServer::Dropped() const { return impl_->dropped; }

}  // namespace ubersim::transport
