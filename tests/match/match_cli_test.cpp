// SPDX-License-Identifier: Apache-2.0
// `ubersim run --referee builtin --tracker --record` as a user runs it, received as a team's
// software receives it (INADDR_ANY, groups joined on loopback), then the recorded log played back
// with `ubersim replay` and compared with what went out: bit for bit, type by type, in order.
#include <gtest/gtest.h>

#include <filesystem>
#include <future>
#include <set>

#include "../common/multicast_receiver.hpp"
#include "../common/run_ubersim.hpp"
#include "ssl_gc_referee_message.pb.h"
#include "ssl_log.hpp"
#include "ssl_vision_wrapper.pb.h"
#include "ssl_vision_wrapper_tracked.pb.h"

namespace {

namespace fs = std::filesystem;
using ubersim::testing::CliResult;
using ubersim::testing::Receiver;
using ubersim::testing::RunUbersim;

// This test's ports (42xxx, not the league's), so that parallel tests keep apart.
constexpr int kRun = 42000, kReplay = 42100;

std::vector<ubersim::sslog::LogRecord> ReadAll(const fs::path& file) {
  std::vector<ubersim::sslog::LogRecord> out;
  ubersim::sslog::LogReader reader(file.string());
  while (auto r = reader.Next()) out.push_back(*r);
  return out;
}

std::vector<std::string> OfType(const std::vector<ubersim::sslog::LogRecord>& records, std::int32_t type) {
  std::vector<std::string> out;
  for (const auto& r : records) {
    if (r.type == type) out.push_back(r.payload);
  }
  return out;
}

// Reads every receiver in turn while `process` runs, and what is left once it ended: sockets
// drained together so that none overflows while another is read.
std::vector<std::vector<std::string>> DrainWhile(std::future<CliResult>& process, std::vector<Receiver*> receivers,
                                                 CliResult& result) {
  std::vector<std::vector<std::string>> got(receivers.size());
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  for (;;) {
    const bool ended = process.wait_for(std::chrono::seconds(0)) == std::future_status::ready;
    bool any = false;
    for (std::size_t i = 0; i < receivers.size(); ++i) {
      auto batch = receivers[i]->Receive(100000, std::chrono::steady_clock::now());
      any = any || !batch.empty();
      got[i].insert(got[i].end(), batch.begin(), batch.end());
    }
    if ((ended && !any) || std::chrono::steady_clock::now() > deadline) break;
  }
  result = process.get();
  return got;
}

TEST(MatchCli, RefereeAndTrackerGoOutAsRecordedAndTheLogReplaysBitIdentically) {
  const fs::path dir = fs::temp_directory_path() / ("ubersim-match-cli-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path log = dir / "match.log.gz";

  Receiver referee(kRun + 3, {"224.5.23.1"}), tracker(kRun + 10, {"224.5.23.2"});
  ASSERT_TRUE(referee.Ok() && tracker.Ok()) << "cannot bind the test's ports";
  auto run = std::async(std::launch::async, [&] {
    return RunUbersim("run div-b --local-only --no-viewer --no-transport ssl_simulation --no-transport grsim --fast "
                      "--duration 12 -q --referee builtin --tracker --vision-port " + std::to_string(kRun + 6) +
                      " --referee-port " + std::to_string(kRun + 3) + " --tracker-port " + std::to_string(kRun + 10) +
                      " --record " + log.string());
  });
  CliResult r;
  const auto received = DrainWhile(run, {&referee, &tracker}, r);
  const auto& got_referee = received[0];  // 12 s at 40 Hz plus one per command
  const auto& got_tracker = received[1];  // 60 Hz
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("publishing referee: udp multicast 224.5.23.1:42003 via lo 127.0.0.1 (local only)"),
            std::string::npos) << r.output;

  // Every Referee datagram decodes; the counter rises by one per command from 0; the match starts
  // as the game controller starts one.
  ASSERT_GE(got_referee.size(), 400u);
  std::vector<Referee::Command> commands;
  unsigned counter = 0;
  for (std::size_t i = 0; i < got_referee.size(); ++i) {
    Referee m;
    ASSERT_TRUE(m.ParseFromString(got_referee[i])) << "datagram " << i;
    if (i == 0) {
      EXPECT_EQ(m.command_counter(), 0u);
      EXPECT_EQ(m.command(), Referee::HALT);
    }
    ASSERT_TRUE(m.command_counter() == counter || m.command_counter() == counter + 1) << "datagram " << i;
    if (i == 0 || m.command_counter() != counter) commands.push_back(m.command());
    counter = m.command_counter();
  }
  ASSERT_GE(commands.size(), 4u);
  EXPECT_EQ(commands[1], Referee::STOP);
  EXPECT_EQ(commands[2], Referee::PREPARE_KICKOFF_YELLOW);
  EXPECT_EQ(commands[3], Referee::NORMAL_START);

  // Tracked frames: one source, consecutive frame numbers, all 12 robots and the ball.
  ASSERT_GE(got_tracker.size(), 600u);
  std::set<std::string> uuids;
  for (std::size_t i = 0; i < got_tracker.size(); ++i) {
    TrackerWrapperPacket p;
    ASSERT_TRUE(p.ParseFromString(got_tracker[i])) << "tracked frame " << i;
    uuids.insert(p.uuid());
    EXPECT_EQ(p.tracked_frame().frame_number(), i);
    EXPECT_EQ(p.tracked_frame().robots_size(), 12);
    EXPECT_EQ(p.tracked_frame().balls_size(), 1);
  }
  EXPECT_EQ(uuids.size(), 1u);

  // The log holds exactly what went out, with Unix time stamps on the simulation's clock.
  const auto records = ReadAll(log);
  EXPECT_TRUE(OfType(records, 3) == got_referee) << OfType(records, 3).size() << " recorded, " << got_referee.size() << " sent";
  EXPECT_TRUE(OfType(records, 5) == got_tracker) << OfType(records, 5).size() << " recorded, " << got_tracker.size() << " sent";
  const auto vision = OfType(records, 4);
  ASSERT_FALSE(vision.empty());
  SSL_WrapperPacket first;
  ASSERT_TRUE(first.ParseFromString(vision.front()));
  EXPECT_TRUE(first.has_geometry());
  std::int64_t previous = 0, first_tracker = -1, last_tracker = -1;
  for (const auto& rec : records) {
    EXPECT_GE(rec.timestamp_ns, previous);
    previous = rec.timestamp_ns;
    if (rec.type == 5) {
      if (first_tracker < 0) first_tracker = rec.timestamp_ns;
      last_tracker = rec.timestamp_ns;
    }
    EXPECT_TRUE(rec.type == 3 || rec.type == 4 || rec.type == 5) << rec.type;
  }
  EXPECT_GT(first_tracker, 1'700'000'000'000'000'000LL);  // Unix ns, not simulated time
  // 12 simulated seconds between the first and the last frame, whatever the wall clock did.
  EXPECT_NEAR(static_cast<double>(last_tracker - first_tracker) * 1e-9, 12.0, 0.05);

  // Played back: each type to its port, every payload unchanged and in order.
  Receiver v2(kReplay + 6, {"224.5.23.2"}), t2(kReplay + 10, {"224.5.23.2"}), r2(kReplay + 3, {"224.5.23.1"});
  ASSERT_TRUE(v2.Ok() && t2.Ok() && r2.Ok());
  auto replay = std::async(std::launch::async, [&] {
    return RunUbersim("replay " + log.string() + " --local-only --speed 0 --vision-port " + std::to_string(kReplay + 6) +
                      " --tracker-port " + std::to_string(kReplay + 10) + " --referee-port " + std::to_string(kReplay + 3));
  });
  CliResult rr;
  const auto replayed = DrainWhile(replay, {&v2, &t2, &r2}, rr);
  const auto& replay_vision = replayed[0];
  const auto& replay_tracker = replayed[1];
  const auto& replay_referee = replayed[2];
  ASSERT_EQ(rr.exit_code, 0) << rr.output;
  EXPECT_TRUE(replay_vision == vision) << replay_vision.size() << " of " << vision.size();
  EXPECT_TRUE(replay_tracker == got_tracker) << replay_tracker.size() << " of " << got_tracker.size();
  EXPECT_TRUE(replay_referee == got_referee) << replay_referee.size() << " of " << got_referee.size();
  fs::remove_all(dir);
}

}  // namespace
