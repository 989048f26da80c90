// SPDX-License-Identifier: Apache-2.0
#include "transport_common/multicast_sender.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <mutex>
#include <optional>
#include <stdexcept>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/multicast.hpp>
#include <boost/asio/ip/udp.hpp>
#include <boost/asio/ip/unicast.hpp>

#include "transport_common/network.hpp"
#include "transport_common/udp_server.hpp"

namespace ubersim::transport {

namespace asio = boost::asio;
using asio::ip::udp;
using SteadyClock = std::chrono::steady_clock;

namespace {

// How often the interfaces behind "auto" and the host's group memberships are read again: a
// receiver that joins late is served within a frame or two, a laptop that changes network within
// a few seconds.
constexpr auto kMembershipRefresh = std::chrono::milliseconds(100);
constexpr auto kInterfaceRefresh = std::chrono::seconds(2);

}  // namespace

/// One outgoing interface with its own socket (IP_MULTICAST_IF is per socket).
struct Route {
  std::string address;  // "" for unicast, "0.0.0.0" for the system's choice
  std::string interface_name;  // "" when unknown
  bool loopback = false;
  std::unique_ptr<udp::socket> socket;
};

struct MulticastSender::Impl {
  Options options;
  asio::io_context io;  // only to own the sockets; sends are synchronous
  UdpEndpoint destination;
  bool multicast = false;
  bool follows_network = false;  // "auto" among the interfaces
  mutable std::mutex mutex;
  std::vector<Route> routes;
  std::optional<std::vector<std::string>> joined;  // interfaces with a local member of the group
  SteadyClock::time_point joined_at{}, routes_at{};
  std::string last_error;
  std::atomic<std::uint64_t> sent{0};
  std::atomic<std::uint64_t> failed{0};

  [[noreturn]] void Fail(const std::string& where, const std::string& step, const boost::system::error_code& ec) const {
    throw std::runtime_error(options.name + ": cannot send to " + ToString(destination) + " via " + where + ": " +
                             step + ": " + ec.message());
  }

  Route Open(const std::string& address) {
    Route r;
    r.address = address;
    r.socket = std::make_unique<udp::socket>(io);
    boost::system::error_code ec;
    r.socket->open(destination.protocol(), ec);
    if (ec) Fail(address, "open", ec);
    if (!multicast) {
      r.socket->set_option(asio::ip::unicast::hops(options.ttl), ec);
      if (ec) Fail(address, "TTL", ec);
      return r;
    }
    r.socket->set_option(asio::ip::multicast::hops(options.ttl), ec);
    if (ec) Fail(address, "TTL", ec);
    r.socket->set_option(asio::ip::multicast::enable_loopback(options.loopback), ec);
    if (ec) Fail(address, "loopback", ec);
    if (address != "0.0.0.0") {
      const UdpEndpoint iface = MakeEndpoint(address, 0, options.name + " interface");
      if (!iface.address().is_v4() || !destination.address().is_v4()) {
        Fail(address, "interface", asio::error::address_family_not_supported);
      }
      r.socket->set_option(asio::ip::multicast::outbound_interface(iface.address().to_v4()), ec);
      if (ec) Fail(address, "interface", ec);
      const std::optional<Ipv4Interface> i = InterfaceWithAddress(address);
      r.interface_name = i ? i->name : std::string();
      r.loopback = i ? i->loopback : iface.address().is_loopback();
    }
    return r;
  }

  // Opens a socket per interface the setting stands for now, keeping those already open. An
  // address that cannot be used is fatal at start (the setting is wrong) and reported later (a
  // network went away).
  void Resolve(bool at_start) {
    std::vector<std::string> wanted = {""};
    if (multicast) wanted = ResolveAddresses(options.interfaces, options.local_only);
    std::vector<Route> next;
    for (const std::string& a : wanted) {
      auto old = std::find_if(routes.begin(), routes.end(), [&](const Route& r) { return r.address == a; });
      if (old != routes.end()) {
        next.push_back(std::move(*old));
        continue;
      }
      try {
        next.push_back(Open(a));
      } catch (const std::runtime_error& e) {
        if (at_start) throw;
        last_error = e.what();
      }
    }
    routes = std::move(next);
    routes_at = SteadyClock::now();
  }

  // True when the loopback copy would reach local receivers twice: a local socket joined the
  // group on another interface that is sent on, and what is looped back there reaches them all.
  bool LoopbackRedundant() const {
    if (!joined) return false;  // unknown: better twice than never
    for (const Route& r : routes) {
      if (r.loopback || r.interface_name.empty()) continue;
      if (std::find(joined->begin(), joined->end(), r.interface_name) != joined->end()) return true;
    }
    return false;
  }
};

MulticastSender::MulticastSender(const Options& options) : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  s.options = options;
  if (options.group.empty()) throw std::runtime_error(options.name + ": no destination address");
  s.destination = MakeEndpoint(options.group, options.port, options.name);
  s.multicast = s.destination.address().is_multicast();
  s.follows_network =
      !options.local_only && std::find(options.interfaces.begin(), options.interfaces.end(), "auto") != options.interfaces.end();
  if (options.ttl < 0 || options.ttl > 255) {
    throw std::runtime_error(options.name + ": TTL " + std::to_string(options.ttl) + " is outside 0..255");
  }
  s.Resolve(true);
}

MulticastSender::~MulticastSender() {
  boost::system::error_code ignored;
  for (Route& r : impl_->routes) r.socket->close(ignored);
}

bool MulticastSender::Send(std::span<const std::uint8_t> bytes) {
  Impl& s = *impl_;
  std::lock_guard lock(s.mutex);
  const auto now = SteadyClock::now();
  if (s.follows_network && now - s.routes_at >= kInterfaceRefresh) s.Resolve(false);
  if (s.multicast && s.routes.size() > 1 && now - s.joined_at >= kMembershipRefresh) {
    s.joined = InterfacesJoined(s.options.group);
    s.joined_at = now;
  }
  const bool skip_loopback = s.routes.size() > 1 && s.LoopbackRedundant();
  bool ok = !s.routes.empty();
  if (!ok) s.last_error = "no interface to send on";
  for (Route& r : s.routes) {
    if (r.loopback && skip_loopback) continue;
    boost::system::error_code ec;
    r.socket->send_to(asio::buffer(bytes.data(), bytes.size()), s.destination, 0, ec);
    if (ec) {
      ok = false;
      s.last_error = (r.address.empty() ? std::string() : "via " + r.address + ": ") + ec.message();
    }
  }
  ++(ok ? s.sent : s.failed);
  return ok;
}

std::string MulticastSender::Describe() const {
  std::lock_guard lock(impl_->mutex);
  const Impl& s = *impl_;
  if (!s.multicast) return "udp " + ToString(s.destination);
  std::string out = "udp multicast " + ToString(s.destination) + " via ";
  for (std::size_t i = 0; i < s.routes.size(); ++i) {
    out += (i == 0 ? "" : " and ") + DescribeAddress(s.routes[i].address);
  }
  if (s.follows_network) out += " (auto: loopback and the default route's interface)";
  if (s.options.local_only) out += " (local only)";
  return out;
}

std::vector<std::string> MulticastSender::Interfaces() const {
  std::lock_guard lock(impl_->mutex);
  std::vector<std::string> out;
  for (const Route& r : impl_->routes) out.push_back(r.address);
  return out;
}

std::string MulticastSender::LastError() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->last_error;
}

std::uint64_t MulticastSender::Sent() const { return impl_->sent; }
std::uint64_t MulticastSender::Failed() const { return impl_->failed; }

}  // namespace ubersim::transport
