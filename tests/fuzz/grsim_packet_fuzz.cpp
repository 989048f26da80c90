// SPDX-License-Identifier: Apache-2.0
// Fuzz target: one datagram on the grsim transport's command port, handled as its receive thread
// does (grsim_transport.cpp): parsed as a grSim_Packet, translated into events, then the robot
// status it would send back, serialised.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "fuzz_checks.hpp"
#include "fuzz_world.hpp"
#include "grsim_packet.pb.h"
#include "grsim_translator.hpp"

namespace {

using ubersim::Event;
using ubersim::grsim::StatusTracker;
using ubersim::grsim::Translator;
using ubersim::grsim::WorldView;

WorldView View(const ubersim::WorldSnapshot& s) {
  WorldView w;
  w.known = true;
  for (const ubersim::RobotState& r : s.robots) w.robots.push_back(r.id);
  w.ball_position = s.ball.pose.position;
  w.ball_radius = s.ball.radius;
  w.half_length = ubersim::fuzz::kHalfCarpetLength;
  w.half_width = ubersim::fuzz::kHalfCarpetWidth;
  return w;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  grSim_Packet packet;
  if (!packet.ParseFromArray(data, static_cast<int>(size))) return 0;

  static const ubersim::WorldSnapshot snapshot = ubersim::fuzz::Snapshot();
  // Before the first snapshot (robot ids unchecked) and after it.
  for (const WorldView& world : {WorldView{}, View(snapshot)}) {
    Translator translator(/*spinner_speed=*/400.0);
    StatusTracker status;
    status.Observe(snapshot.robots, translator);
    std::vector<Event> events;
    std::vector<std::string> rejects;
    // Twice: the second time the spinners are known and only changes reach the dribblers.
    for (int i = 0; i < 2; ++i) translator.Translate(packet, world, events, rejects);
    ubersim::fuzz::CheckFinite(events);
    // The kickers fire; the status tells flat from chip by the translator's last kick angle.
    std::vector<ubersim::RobotState> fired = snapshot.robots;
    for (ubersim::RobotState& r : fired) r.kicker_ready = false;
    status.Observe(fired, translator);
    const auto [blue, yellow] = status.TakeChanged();
    std::string bytes;
    ubersim::fuzz::Check(blue.SerializeToString(&bytes) && yellow.SerializeToString(&bytes),
                         "robot status does not serialise");
  }
  return 0;
}
