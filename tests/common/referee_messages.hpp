// SPDX-License-Identifier: Apache-2.0
// A Referee message with every required field set, as the game controller sends before a match:
// the base the tests' messages are built on.
#pragma once

#include <cstdint>
#include <string>

#include "ssl_gc_referee_message.pb.h"

namespace ubersim::testing {

/// HALT before the first half, command counter 0, both teams' required info (4 timeouts of 300 s,
/// keeper 0, no score or cards), time stamps `t_us`.
inline Referee HaltedReferee(std::uint64_t t_us, const std::string& yellow = "Yellow", const std::string& blue = "Blue") {
  Referee r;
  r.set_packet_timestamp(t_us);
  r.set_stage(Referee::NORMAL_FIRST_HALF_PRE);
  r.set_command(Referee::HALT);
  r.set_command_counter(0);
  r.set_command_timestamp(t_us);
  for (Referee::TeamInfo* t : {r.mutable_yellow(), r.mutable_blue()}) {
    t->set_name(t == r.mutable_yellow() ? yellow : blue);
    t->set_score(0);
    t->set_red_cards(0);
    t->set_yellow_cards(0);
    t->set_timeouts(4);
    t->set_timeout_time(300'000'000);
    t->set_goalkeeper(0);
  }
  return r;
}

}  // namespace ubersim::testing
