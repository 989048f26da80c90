// SPDX-License-Identifier: Apache-2.0
// A multicast receiver as a team's software opens one: bound to INADDR_ANY:port, the groups joined
// on loopback (tests never use the machine's real interfaces).
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

namespace ubersim::testing {

// A UDP socket on INADDR_ANY:port that joined `groups` on loopback, as a team's software does.
class Receiver {
 public:
  Receiver(std::uint16_t port, const std::vector<std::string>& groups) {
    fd_ = ::socket(AF_INET, SOCK_DGRAM, 0);
    const int one = 1;
    ::setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    const int buffer = 4 << 20;
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &buffer, sizeof buffer);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(port);
    addr.sin_addr.s_addr = htonl(INADDR_ANY);
    ok_ = ::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0;
    for (const std::string& g : groups) {
      ip_mreq m{};
      ::inet_pton(AF_INET, g.c_str(), &m.imr_multiaddr);
      ::inet_pton(AF_INET, "127.0.0.1", &m.imr_interface);
      ok_ = ok_ && ::setsockopt(fd_, IPPROTO_IP, IP_ADD_MEMBERSHIP, &m, sizeof m) == 0;
    }
    timeval tv{0, 200'000};
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  }
  ~Receiver() { ::close(fd_); }
  Receiver(const Receiver&) = delete;
  Receiver& operator=(const Receiver&) = delete;

  bool Ok() const { return ok_; }
  /// Datagrams until `count` came or none came for 200 ms after `until`.
  std::vector<std::string> Receive(std::size_t count, std::chrono::steady_clock::time_point until) {
    std::vector<std::string> out;
    std::vector<char> buf(70'000);
    while (out.size() < count) {
      const ssize_t n = ::recv(fd_, buf.data(), buf.size(), 0);
      if (n >= 0) {
        out.emplace_back(buf.data(), static_cast<std::size_t>(n));
        times_.push_back(std::chrono::steady_clock::now());
      } else if (std::chrono::steady_clock::now() > until) {
        break;
      }
    }
    return out;
  }
  const std::vector<std::chrono::steady_clock::time_point>& Times() const { return times_; }

 private:
  int fd_ = -1;
  bool ok_ = false;
  std::vector<std::chrono::steady_clock::time_point> times_;
};

}  // namespace ubersim::testing
