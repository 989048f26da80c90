// SPDX-License-Identifier: Apache-2.0
#include "transport_common/udp_server.hpp"

#include <atomic>
#include <exception>
#include <map>
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

// One bound socket with its receive buffer.
struct Listener {
  explicit Listener(asio::io_context& io) : socket(io) {}
  udp::socket socket;
  std::vector<std::uint8_t> buffer;
  UdpEndpoint sender;
};

struct UdpServer::Impl {
  Options options;
  Handler handler;
  DropHandler on_drop;
  asio::io_context io;
  std::vector<std::unique_ptr<Listener>> listeners;
  Listener* receiving = nullptr;  // the one whose datagram the handler holds (receive thread)
  std::map<asio::ip::address, Listener*> last_heard;  // which socket an address last spoke to (receive thread)
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

  void Receive(Listener& l) {
    l.socket.async_receive_from(asio::buffer(l.buffer), l.sender, [this, &l](const boost::system::error_code& ec, std::size_t n) {
      if (ec == asio::error::operation_aborted || !l.socket.is_open()) return;
      receiving = &l;
      if (ec) {
        // E.g. an ICMP "port unreachable" after a reply to a closed port: report, keep serving.
        Drop(DropReason::Kind::kReceiveFailed, "receive failed: " + ec.message(), l.sender);
      } else if (n > options.max_datagram) {
        // The buffer is one byte longer than allowed, so a longer datagram shows as n > max.
        Drop(DropReason::Kind::kOversized, "datagram longer than " + std::to_string(options.max_datagram) + " bytes",
             l.sender);
      } else {
        ++received;
        last_heard[l.sender.address()] = &l;
        try {
          handler(std::span<const std::uint8_t>(l.buffer.data(), n), l.sender);
        } catch (const std::exception& e) {
          Drop(DropReason::Kind::kHandlerThrew, std::string("handler threw: ") + e.what(), l.sender);
        }
      }
      receiving = nullptr;
      Receive(l);
    });
  }

  // The socket a reply to `to` leaves from (receive thread).
  Listener& ReplySocket(const UdpEndpoint& to) {
    if (receiving) return *receiving;
    const auto heard = last_heard.find(to.address());
    return heard != last_heard.end() ? *heard->second : *listeners.front();
  }

  bool SendNow(Listener& from, const UdpEndpoint& to, std::span<const std::uint8_t> bytes) {
    boost::system::error_code ec;
    from.socket.send_to(asio::buffer(bytes.data(), bytes.size()), to, 0, ec);
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
  if (options.addresses.empty()) throw std::invalid_argument(options.name + ": no address to bind");
  impl_->options = options;
  impl_->handler = std::move(handler);
  impl_->on_drop = std::move(on_drop);
  std::uint16_t port = options.port;
  for (const std::string& address : options.addresses) {
    const UdpEndpoint endpoint = MakeEndpoint(address, port, options.name);
    auto l = std::make_unique<Listener>(impl_->io);
    l->buffer.resize(options.max_datagram + 1);
    boost::system::error_code ec;
    l->socket.open(endpoint.protocol(), ec);
    if (!ec) l->socket.bind(endpoint, ec);
    if (ec) {
      throw std::runtime_error(options.name + ": cannot bind UDP " + ToString(endpoint) + ": " + ec.message());
    }
    if (port == 0) port = l->socket.local_endpoint().port();  // the system's pick, for every address
    impl_->listeners.push_back(std::move(l));
  }
}

UdpServer::~UdpServer() { Stop(); }

void UdpServer::Start() {
  if (impl_->running.exchange(true)) return;
  for (auto& l : impl_->listeners) impl_->Receive(*l);
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
  for (auto& l : impl_->listeners) l->socket.close(ignored);
}

bool UdpServer::Reply(const UdpEndpoint& to, std::span<const std::uint8_t> bytes) {
  if (!impl_->listeners.front()->socket.is_open() || impl_->io.stopped()) return false;
  if (impl_->io.get_executor().running_in_this_thread()) {
    return impl_->SendNow(impl_->ReplySocket(to), to, bytes);
  }
  // From another thread: hand a copy to the receive thread, which owns the sockets.
  auto copy = std::make_shared<std::vector<std::uint8_t>>(bytes.begin(), bytes.end());
  asio::post(impl_->io, [impl = impl_.get(), to, copy] { impl->SendNow(impl->ReplySocket(to), to, *copy); });
  return true;
}

UdpEndpoint UdpServer::LocalEndpoint() const { return LocalEndpoints().front(); }

std::vector<UdpEndpoint> UdpServer::LocalEndpoints() const {
  std::vector<UdpEndpoint> out;
  for (const auto& l : impl_->listeners) {
    boost::system::error_code ec;
    const UdpEndpoint e = l->socket.local_endpoint(ec);
    out.push_back(ec ? UdpEndpoint() : e);
  }
  return out;
}

std::uint64_t UdpServer::Received() const { return impl_->received; }
std::uint64_t UdpServer::Dropped() const { return impl_->dropped; }

}  // namespace ubersim::transport
