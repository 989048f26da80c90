// SPDX-License-Identifier: Apache-2.0
#include "transport_common/network.hpp"

#include <arpa/inet.h>
#include <ifaddrs.h>
#include <net/if.h>
#include <netinet/in.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>

namespace ubersim::transport {
namespace {

std::optional<std::string> ReadFile(const char* path) {
  std::ifstream in(path);
  if (!in) return std::nullopt;
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// The kernel prints addresses in /proc/net as the raw 32-bit word in host byte order ("%08X"),
// so the bytes of the parsed number are the address's bytes in network order on any host.
std::string AddressFromProcHex(const std::string& hex) {
  std::uint32_t raw = 0;
  try {
    raw = static_cast<std::uint32_t>(std::stoul(hex, nullptr, 16));
  } catch (const std::exception&) {
    return {};
  }
  in_addr a{};
  std::memcpy(&a.s_addr, &raw, sizeof raw);
  char text[INET_ADDRSTRLEN] = {};
  return inet_ntop(AF_INET, &a, text, sizeof text) ? std::string(text) : std::string();
}

}  // namespace

std::vector<Ipv4Interface> ListIpv4Interfaces() {
  std::vector<Ipv4Interface> out;
  ifaddrs* list = nullptr;
  if (getifaddrs(&list) != 0) return out;
  for (const ifaddrs* i = list; i; i = i->ifa_next) {
    if (!i->ifa_addr || i->ifa_addr->sa_family != AF_INET) continue;
    char text[INET_ADDRSTRLEN] = {};
    const auto* sin = reinterpret_cast<const sockaddr_in*>(i->ifa_addr);
    if (!inet_ntop(AF_INET, &sin->sin_addr, text, sizeof text)) continue;
    Ipv4Interface iface;
    iface.name = i->ifa_name;
    iface.address = text;
    iface.loopback = (i->ifa_flags & IFF_LOOPBACK) != 0;
    iface.up = (i->ifa_flags & IFF_UP) && (i->ifa_flags & IFF_RUNNING);
    iface.multicast = (i->ifa_flags & IFF_MULTICAST) != 0;
    out.push_back(std::move(iface));
  }
  freeifaddrs(list);
  return out;
}

std::string ParseDefaultRoute(const std::string& proc_net_route) {
  std::istringstream in(proc_net_route);
  std::string line;
  std::getline(in, line);  // header
  std::string best;
  long best_metric = std::numeric_limits<long>::max();
  while (std::getline(in, line)) {
    // Iface Destination Gateway Flags RefCnt Use Metric Mask ...
    std::istringstream f(line);
    std::string iface, destination, gateway, flags, refcnt, use, metric, mask;
    if (!(f >> iface >> destination >> gateway >> flags >> refcnt >> use >> metric >> mask)) continue;
    if (destination != "00000000" || mask != "00000000") continue;
    unsigned long route_flags = 0;
    long m = 0;
    try {
      route_flags = std::stoul(flags, nullptr, 16);
      m = std::stol(metric);
    } catch (const std::exception&) {
      continue;
    }
    if (!(route_flags & 0x1)) continue;  // RTF_UP
    if (m < best_metric) {
      best_metric = m;
      best = iface;
    }
  }
  return best;
}

std::optional<Ipv4Interface> DefaultRouteInterface() {
  const std::optional<std::string> routes = ReadFile("/proc/net/route");
  if (!routes) return std::nullopt;
  const std::string name = ParseDefaultRoute(*routes);
  if (name.empty()) return std::nullopt;
  for (Ipv4Interface& i : ListIpv4Interfaces()) {
    if (i.name == name) return i;
  }
  return std::nullopt;
}

std::optional<Ipv4Interface> InterfaceWithAddress(const std::string& address) {
  for (Ipv4Interface& i : ListIpv4Interfaces()) {
    if (i.address == address) return i;
  }
  return std::nullopt;
}

std::vector<std::string> ParseIgmpMemberships(const std::string& proc_net_igmp, const std::string& group) {
  // An interface line ("1\tlo        :     2      V3") is followed by one indented line per group
  // ("\t\t\t\t021705E0     1 0:00000000\t\t0").
  std::vector<std::string> out;
  std::istringstream in(proc_net_igmp);
  std::string line;
  std::getline(in, line);  // header
  std::string current;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    std::istringstream f(line);
    if (line[0] != '\t' && line[0] != ' ') {
      std::string index;
      f >> index >> current;
      if (!current.empty() && current.back() == ':') current.pop_back();
      continue;
    }
    std::string hex;
    f >> hex;
    if (!current.empty() && AddressFromProcHex(hex) == group &&
        std::find(out.begin(), out.end(), current) == out.end()) {
      out.push_back(current);
    }
  }
  return out;
}

std::optional<std::vector<std::string>> InterfacesJoined(const std::string& group) {
  const std::optional<std::string> text = ReadFile("/proc/net/igmp");
  if (!text) return std::nullopt;
  return ParseIgmpMemberships(*text, group);
}

std::vector<std::string> ResolveAddresses(const std::vector<std::string>& setting, bool local_only) {
  if (local_only) return {kLoopback};
  std::vector<std::string> out;
  const auto add = [&out](const std::string& a) {
    if (std::find(out.begin(), out.end(), a) == out.end()) out.push_back(a);
  };
  for (const std::string& s : setting) {
    if (s == "auto") {
      add(kLoopback);
      if (const auto d = DefaultRouteInterface(); d && !d->loopback) add(d->address);
    } else {
      add(s.empty() ? std::string("0.0.0.0") : s);
    }
  }
  if (out.empty()) add(kLoopback);
  return out;
}

std::vector<std::string> AddressSetting(const ParamView& params, const std::string& key, const std::string& fallback) {
  if (!params.Has(key)) return {fallback};
  const ParamView v = params[key];
  if (!v.IsArray()) return {v.AsString()};
  std::vector<std::string> out;
  for (std::size_t i = 0; i < v.Size(); ++i) out.push_back(v.At(i).AsString());
  if (out.empty()) throw v.Error("needs at least one address (or \"auto\")");
  return out;
}

std::string DescribeAddress(const std::string& address) {
  if (address == "0.0.0.0") return "every interface (0.0.0.0)";
  if (const auto i = InterfaceWithAddress(address)) return i->name + " " + address;
  return address;
}

}  // namespace ubersim::transport
