// SPDX-License-Identifier: Apache-2.0
// UdpServer, MulticastSender, units, wire clock and reject log, with real sockets on loopback.
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/multicast.hpp>
#include <boost/asio/ip/udp.hpp>
#include <gtest/gtest.h>

#include "transport_common/multicast_sender.hpp"
#include "transport_common/network.hpp"
#include "transport_common/reject_log.hpp"
#include "transport_common/udp_server.hpp"
#include "transport_common/wire_clock.hpp"
#include "transport_common/wire_units.hpp"

namespace {

namespace asio = boost::asio;
using asio::ip::udp;
using namespace ubersim::transport;
using namespace std::chrono_literals;

std::span<const std::uint8_t> Bytes(const std::string& s) {
  return {reinterpret_cast<const std::uint8_t*>(s.data()), s.size()};
}

// A plain blocking client socket on 127.0.0.1 with a receive timeout.
struct Client {
  asio::io_context io;
  udp::socket socket{io, udp::endpoint(asio::ip::make_address("127.0.0.1"), 0)};
  Client() {
    timeval tv{2, 0};
    setsockopt(socket.native_handle(), SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  }
  void Send(const std::string& s, const udp::endpoint& to) { socket.send_to(asio::buffer(s), to); }
  std::string Receive() {
    std::vector<char> buf(70000);
    udp::endpoint from;
    boost::system::error_code ec;
    const std::size_t n = socket.receive_from(asio::buffer(buf), from, 0, ec);
    return ec ? std::string("<timeout>") : std::string(buf.data(), n);
  }
};

// Collects datagrams from the server's thread.
struct Inbox {
  std::mutex mutex;
  std::condition_variable cv;
  std::vector<std::string> items;
  std::vector<std::string> drops;
  void Add(std::vector<std::string>& to, std::string s) {
    {
      std::lock_guard lock(mutex);
      to.push_back(std::move(s));
    }
    cv.notify_all();
  }
  bool WaitFor(std::vector<std::string>& v, std::size_t n) {
    std::unique_lock lock(mutex);
    return cv.wait_for(lock, 3s, [&] { return v.size() >= n; });
  }
};

TEST(UdpServer, HandsOverEachDatagramWithItsSenderAndReplies) {
  Inbox inbox;
  UdpServer* server_ptr = nullptr;
  UdpServer server({{"127.0.0.1"}, 0, 1000, "test"}, [&](std::span<const std::uint8_t> b, const UdpEndpoint& from) {
    inbox.Add(inbox.items, std::string(b.begin(), b.end()));
    server_ptr->Reply(from, Bytes("pong:" + std::string(b.begin(), b.end())));
  });
  server_ptr = &server;
  server.Start();
  ASSERT_NE(server.LocalEndpoint().port(), 0);
  Client client;
  client.Send("ping", server.LocalEndpoint());
  EXPECT_EQ(client.Receive(), "pong:ping");
  ASSERT_TRUE(inbox.WaitFor(inbox.items, 1));
  EXPECT_EQ(inbox.items[0], "ping");
  EXPECT_EQ(server.Received(), 1u);
  // From another thread: queued to the receive thread.
  EXPECT_TRUE(server.Reply(client.socket.local_endpoint(), Bytes("hello")));
  EXPECT_EQ(client.Receive(), "hello");
  server.Stop();
  server.Stop();  // idempotent
  EXPECT_FALSE(server.Reply(client.socket.local_endpoint(), Bytes("late")));
}

TEST(UdpServer, DropsOversizedDatagramsAndSurvivesAThrowingHandler) {
  Inbox inbox;
  UdpServer server(
      {{"127.0.0.1"}, 0, 100, "test"},
      [&](std::span<const std::uint8_t> b, const UdpEndpoint&) {
        if (b.size() == 1) throw std::runtime_error("boom");
        inbox.Add(inbox.items, std::string(b.begin(), b.end()));
      },
      [&](const std::string& why, const UdpEndpoint&) { inbox.Add(inbox.drops, why); });
  server.Start();
  Client client;
  client.Send(std::string(101, 'x'), server.LocalEndpoint());
  client.Send("x", server.LocalEndpoint());
  client.Send(std::string(100, 'y'), server.LocalEndpoint());
  client.Send("", server.LocalEndpoint());
  ASSERT_TRUE(inbox.WaitFor(inbox.items, 2));
  ASSERT_TRUE(inbox.WaitFor(inbox.drops, 2));
  EXPECT_EQ(inbox.items[0], std::string(100, 'y'));  // whole, never cut short
  EXPECT_EQ(inbox.items[1], "");
  EXPECT_NE(inbox.drops[0].find("longer than 100 bytes"), std::string::npos) << inbox.drops[0];
  EXPECT_NE(inbox.drops[1].find("handler threw: boom"), std::string::npos) << inbox.drops[1];
  EXPECT_EQ(server.Dropped(), 2u);
}

// A transport that must answer every request (ssl_simulation) replies to an oversized one from
// the drop handler, which knows the kind of drop and the sender.
TEST(UdpServer, TheDropHandlerKnowsTheKindAndCanReplyToTheSender) {
  Inbox inbox;
  UdpServer* server_ptr = nullptr;
  UdpServer server(
      {{"127.0.0.1"}, 0, 100, "test"}, [&](std::span<const std::uint8_t>, const UdpEndpoint&) {},
      [&](const DropReason& why, const UdpEndpoint& from) {
        if (why.kind == DropReason::Kind::kOversized) server_ptr->Reply(from, Bytes("too long: " + why.text));
        inbox.Add(inbox.drops, why.text);
      });
  server_ptr = &server;
  server.Start();
  Client client;
  client.Send(std::string(101, 'x'), server.LocalEndpoint());
  EXPECT_EQ(client.Receive(), "too long: datagram longer than 100 bytes");
  ASSERT_TRUE(inbox.WaitFor(inbox.drops, 1));
  EXPECT_EQ(server.Dropped(), 1u);
  EXPECT_EQ(server.Received(), 0u);
}

TEST(UdpServer, APortInUseIsAnErrorNamingAddressAndPort) {
  UdpServer first({{"127.0.0.1"}, 0, 100, "first"}, [](auto, const auto&) {});
  const int port = first.LocalEndpoint().port();
  try {
    UdpServer second({{"127.0.0.1"}, static_cast<std::uint16_t>(port), 100, "grsim"}, [](auto, const auto&) {});
    FAIL() << "bound a port in use";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("grsim: cannot bind UDP 127.0.0.1:" + std::to_string(port)), std::string::npos) << what;
    EXPECT_NE(what.find("in use"), std::string::npos) << what;
  }
  EXPECT_THROW(UdpServer({{"localhost"}, 0, 100, "x"}, [](auto, const auto&) {}), std::runtime_error);
}

TEST(MulticastSender, ReachesAReceiverJoinedOnLoopback) {
  asio::io_context io;
  const auto group = asio::ip::make_address("224.5.23.2");
  udp::socket receiver(io, udp::v4());
  receiver.set_option(asio::socket_base::reuse_address(true));
  receiver.bind(udp::endpoint(group, 0));
  receiver.set_option(asio::ip::multicast::join_group(group.to_v4(), asio::ip::make_address_v4("127.0.0.1")));
  timeval tv{2, 0};
  setsockopt(receiver.native_handle(), SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  const std::uint16_t port = receiver.local_endpoint().port();

  MulticastSender sender({"224.5.23.2", port, {"127.0.0.1"}, false, 1, true, "test"});
  EXPECT_EQ(sender.Describe(), "udp multicast 224.5.23.2:" + std::to_string(port) + " via lo 127.0.0.1");
  ASSERT_TRUE(sender.Send(Bytes("frame"))) << sender.LastError();
  std::array<char, 100> buf{};
  boost::system::error_code ec;
  const std::size_t n = receiver.receive(asio::buffer(buf), 0, ec);
  ASSERT_FALSE(ec) << ec.message();
  EXPECT_EQ(std::string(buf.data(), n), "frame");
  EXPECT_EQ(sender.Sent(), 1u);

  EXPECT_EQ(MulticastSender({"224.5.23.2", 10020, {"0.0.0.0"}, false, 1, true, "t"}).Describe(),
            "udp multicast 224.5.23.2:10020 via every interface (0.0.0.0)");
  EXPECT_EQ(MulticastSender({"127.0.0.1", 10020, {"auto"}, false, 1, true, "t"}).Describe(), "udp 127.0.0.1:10020");
  // --local-only: loopback, whatever the setting.
  const MulticastSender local({"224.5.23.2", 10020, {"auto", "0.0.0.0"}, true, 1, true, "t"});
  EXPECT_EQ(local.Interfaces(), std::vector<std::string>{"127.0.0.1"});
  EXPECT_EQ(local.Describe(), "udp multicast 224.5.23.2:10020 via lo 127.0.0.1 (local only)");
  EXPECT_THROW(MulticastSender({"vision.local", 10020, {"127.0.0.1"}, false, 1, true, "t"}), std::runtime_error);
  EXPECT_THROW(MulticastSender({"224.5.23.2", 10020, {"127.0.0.1"}, false, 300, true, "t"}), std::runtime_error);
  // An address no interface has cannot carry multicast: named at start.
  EXPECT_THROW(MulticastSender({"224.5.23.2", 10020, {"192.0.2.77"}, false, 1, true, "t"}), std::runtime_error);
}

// A server on two addresses answers each request from the address it came to (a tool replying to
// the source of the vision packets must hear its answer from there). Every 127/8 address is local.
TEST(UdpServer, ListensOnSeveralAddressesAndRepliesFromTheOneAsked) {
  UdpServer* server_ptr = nullptr;
  UdpServer server({{"127.0.0.1", "127.0.0.2"}, 0, 100, "two"}, [&](std::span<const std::uint8_t> b, const UdpEndpoint& from) {
    server_ptr->Reply(from, b);
  });
  server_ptr = &server;
  ASSERT_EQ(server.LocalEndpoints().size(), 2u);
  const std::uint16_t port = server.LocalEndpoint().port();
  ASSERT_NE(port, 0);
  EXPECT_EQ(server.LocalEndpoints()[1].port(), port);  // one port, chosen once
  server.Start();
  for (const char* address : {"127.0.0.1", "127.0.0.2"}) {
    Client client;
    client.Send(address, UdpEndpoint(asio::ip::make_address(address), port));
    udp::endpoint from;
    std::array<char, 100> buf{};
    boost::system::error_code ec;
    const std::size_t n = client.socket.receive_from(asio::buffer(buf), from, 0, ec);
    ASSERT_FALSE(ec) << ec.message();
    EXPECT_EQ(std::string(buf.data(), n), address);
    EXPECT_EQ(from.address().to_string(), address);
  }
}

TEST(Network, ReadsTheGroupsJoinedPerInterfaceFromProcNetIgmp) {
  // As Linux prints it: the group word in host order (224.5.23.2 is 021705E0 on little endian).
  const std::string text =
      "Idx\tDevice    : Count Querier\tGroup    Users Timer\tReporter\n"
      "1\tlo        :     2      V3\n"
      "\t\t\t\t021705E0     1 0:00000000\t\t0\n"
      "\t\t\t\t010000E0     1 0:00000000\t\t0\n"
      "3\tveth0     :     2      V3\n"
      "\t\t\t\t010000E0     1 0:00000000\t\t0\n"
      "4\twlp2s0    :     2      V3\n"
      "\t\t\t\t021705E0     2 0:00000000\t\t0\n";
  EXPECT_EQ(ParseIgmpMemberships(text, "224.5.23.2"), (std::vector<std::string>{"lo", "wlp2s0"}));
  EXPECT_EQ(ParseIgmpMemberships(text, "224.0.0.1"), (std::vector<std::string>{"lo", "veth0"}));
  EXPECT_TRUE(ParseIgmpMemberships(text, "224.5.23.1").empty());
  EXPECT_TRUE(ParseIgmpMemberships("", "224.5.23.2").empty());
}

TEST(Network, FindsTheDefaultRouteWithTheLowestMetric) {
  const std::string text =
      "Iface\tDestination\tGateway \tFlags\tRefCnt\tUse\tMetric\tMask\t\tMTU\tWindow\tIRTT\n"
      "wlp2s0\t00000000\t0101A8C0\t0003\t0\t0\t600\t00000000\t0\t0\t0\n"
      "eth0\t00000000\t0100000A\t0003\t0\t0\t100\t00000000\t0\t0\t0\n"
      "eth0\t0000000A\t00000000\t0001\t0\t0\t100\t00FFFFFF\t0\t0\t0\n"
      "down0\t00000000\t0100000A\t0002\t0\t0\t1\t00000000\t0\t0\t0\n";
  EXPECT_EQ(ParseDefaultRoute(text), "eth0");
  EXPECT_EQ(ParseDefaultRoute("Iface\tDestination\n"), "");
}

TEST(Network, AutoIsLoopbackFirstAndLocalOnlyIsLoopbackAlone) {
  const std::vector<std::string> automatic = ResolveAddresses({"auto"}, false);
  ASSERT_FALSE(automatic.empty());
  EXPECT_EQ(automatic.front(), "127.0.0.1");
  EXPECT_LE(automatic.size(), 2u);
  EXPECT_EQ(ResolveAddresses({"auto", "10.1.2.3"}, true), std::vector<std::string>{"127.0.0.1"});
  EXPECT_EQ(ResolveAddresses({"10.1.2.3", "10.1.2.3", ""}, false), (std::vector<std::string>{"10.1.2.3", "0.0.0.0"}));
  const auto params = ubersim::ParamView::FromJson(R"({"one": "127.0.0.1", "two": ["auto", "10.0.0.1"], "none": []})");
  EXPECT_EQ(AddressSetting(params, "one", "auto"), std::vector<std::string>{"127.0.0.1"});
  EXPECT_EQ(AddressSetting(params, "two", "auto"), (std::vector<std::string>{"auto", "10.0.0.1"}));
  EXPECT_EQ(AddressSetting(params, "absent", "auto"), std::vector<std::string>{"auto"});
  EXPECT_THROW(AddressSetting(params, "none", "auto"), ubersim::ParamError);
}

TEST(WireUnits, ConvertOnlyAtTheWire) {
  EXPECT_DOUBLE_EQ(MetresToMm(1.5), 1500.0);
  EXPECT_DOUBLE_EQ(MmToMetres(21.5), 0.0215);
  EXPECT_DOUBLE_EQ(RadToDeg(std::numbers::pi), 180.0);
  EXPECT_DOUBLE_EQ(DegToRad(90.0), std::numbers::pi / 2);
  EXPECT_NEAR(RpmToRadPerS(1000.0), 104.71975511965977, 1e-12);
  EXPECT_NEAR(RadPerSToRpm(RpmToRadPerS(1234.0)), 1234.0, 1e-9);
  EXPECT_EQ(MetresToWholeMm(9.0), 9000);
  EXPECT_EQ(MetresToWholeMm(0.0215), 22);  // rounded to nearest
  EXPECT_EQ(MetresToWholeMm(-0.0004), 0);
  EXPECT_EQ(MetresToWholeMm(1e12), std::numeric_limits<std::int32_t>::max());
  EXPECT_EQ(MetresToWholeMm(std::nan("")), 0);
  EXPECT_EQ(WholePixels(118.6), 119u);  // a blob's area: rounded to nearest
  EXPECT_EQ(WholePixels(0.4), 0u);
  EXPECT_EQ(WholePixels(-3.0), 0u);
  EXPECT_EQ(WholePixels(1e12), std::numeric_limits<std::uint32_t>::max());
  EXPECT_EQ(WholePixels(std::nan("")), 0u);
}

TEST(WireClock, UnixStampsAreUnixTimeAtStartPlusSimTime) {
  double unix_now = 1.7e9;
  WireClock clock(TimestampMode::kUnix, [&] { return unix_now; });
  clock.Update(2'000'000'000);  // anchored: 1.7e9 − 2 s
  unix_now += 100.0;            // wall time runs on; the stamps follow sim time only
  EXPECT_DOUBLE_EQ(clock.Seconds(2'500'000'000), 1.7e9 + 0.5);
  // Differences keep the sim's spacing to the resolution of a double near 1.7e9 s (< 1 µs).
  EXPECT_NEAR(clock.Seconds(2'035'000'000) - clock.Seconds(2'000'000'000), 0.035, 1e-6);
  clock.Update(1'000'000'000);  // a reset: anchored again
  EXPECT_DOUBLE_EQ(clock.Seconds(1'000'000'000), 1.7e9 + 100.0);

  WireClock sim(TimestampMode::kSim);
  EXPECT_DOUBLE_EQ(sim.Seconds(1'250'000'000), 1.25);
  EXPECT_EQ(ParseTimestampMode("sim"), TimestampMode::kSim);
  EXPECT_EQ(ParseTimestampMode("unix"), TimestampMode::kUnix);
  EXPECT_THROW(ParseTimestampMode("gps"), std::invalid_argument);
  EXPECT_NEAR(SystemUnixSeconds(), static_cast<double>(std::time(nullptr)), 2.0);
}

struct CapturingLog final : ubersim::Log {
  std::vector<std::string> lines;
  void Write(ubersim::LogLevel, std::string_view m) override { lines.emplace_back(m); }
};

TEST(RejectLog, CountsEveryRejectionAndWritesAtMostOneLinePerInterval) {
  CapturingLog log;
  RejectLog rejects(log, "grSim datagram rejected", 10s);
  for (int i = 0; i < 100; ++i) rejects.Reject("reason " + std::to_string(i));
  ASSERT_EQ(log.lines.size(), 1u);
  EXPECT_EQ(log.lines[0], "grSim datagram rejected: reason 0 (1 since the last report, 1 in total)");
  rejects.Flush();
  ASSERT_EQ(log.lines.size(), 2u);
  EXPECT_EQ(log.lines[1], "grSim datagram rejected: reason 99 (99 since the last report, 100 in total)");
  rejects.Flush();
  EXPECT_EQ(log.lines.size(), 2u);
  EXPECT_EQ(rejects.Count(), 100u);

  RejectLog fast(log, "x", 0ms);
  fast.Reject("a");
  fast.Reject("b");
  EXPECT_EQ(log.lines.size(), 4u);
}

TEST(RejectLog, NamesWhatItCounts) {
  CapturingLog log;
  RejectLog refused(log, "message refused", 10s, "refused");
  refused.Reject("blue: UBERSIM_UNREADABLE");
  ASSERT_EQ(log.lines.size(), 1u);
  EXPECT_EQ(log.lines[0], "message refused: blue: UBERSIM_UNREADABLE (1 refused since the last report, 1 in total)");
}

}  // namespace
