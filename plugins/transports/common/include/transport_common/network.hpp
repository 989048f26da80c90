// SPDX-License-Identifier: Apache-2.0
// What this machine's IPv4 network looks like to a transport: its interfaces, the one that holds
// the default route, the multicast groups joined on each, and what a transport's address setting
// ("auto", an address, a list) stands for. Linux: getifaddrs, /proc/net/route, /proc/net/igmp.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <ubersim/params.hpp>

namespace ubersim::transport {

/// The loopback address every setting falls back to.
inline constexpr char kLoopback[] = "127.0.0.1";

/// One IPv4 address of one interface of this machine.
struct Ipv4Interface {
  std::string name;        ///< "lo", "eth0", "wlp2s0"
  std::string address;     ///< numeric, "192.168.1.5"
  bool loopback = false;   ///< the loopback interface
  bool up = false;         ///< IFF_UP and IFF_RUNNING
  bool multicast = false;  ///< IFF_MULTICAST (tools like the league's Go programs skip interfaces without it)
};

/// Every IPv4 address of this machine's interfaces, in the system's order.
std::vector<Ipv4Interface> ListIpv4Interfaces();

/// The interface (and its first IPv4 address) that holds the IPv4 default route with the lowest
/// metric; nullopt when the machine has no default route (or it has no IPv4 address).
std::optional<Ipv4Interface> DefaultRouteInterface();

/// The interface that carries `address`, nullopt when no interface of this machine has it.
std::optional<Ipv4Interface> InterfaceWithAddress(const std::string& address);

/// Names of the interfaces on which some socket of this host (this network namespace) has joined
/// the IPv4 multicast `group`; nullopt when that cannot be read (no /proc/net/igmp).
std::optional<std::vector<std::string>> InterfacesJoined(const std::string& group);

/// Parses the text of /proc/net/igmp: the interfaces that joined `group` (exposed for tests).
std::vector<std::string> ParseIgmpMemberships(const std::string& proc_net_igmp, const std::string& group);

/// Parses the text of /proc/net/route: the interface of the lowest-metric default route, or ""
/// (exposed for tests).
std::string ParseDefaultRoute(const std::string& proc_net_route);

/// The addresses a transport setting stands for, now. Each entry is "auto" (loopback, plus the
/// default route's interface when there is one), "0.0.0.0" (every interface / the system's
/// choice) or a numeric address; duplicates are dropped, order kept. With `local_only` the
/// answer is loopback alone, whatever the setting.
std::vector<std::string> ResolveAddresses(const std::vector<std::string>& setting, bool local_only);

/// A transport's address setting `key` of `params`: one string or a list of strings; `fallback`
/// when absent ("auto" for the shipped transports). Throws ParamError at an empty list.
std::vector<std::string> AddressSetting(const ParamView& params, const std::string& key, const std::string& fallback);

/// "lo 127.0.0.1", "eth0 192.168.1.5", or the address alone when no interface has it.
std::string DescribeAddress(const std::string& address);

}  // namespace ubersim::transport
