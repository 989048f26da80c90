// SPDX-License-Identifier: Apache-2.0
#include "referee_datagram.hpp"

#include "ssl_gc_game_event.pb.h"
#include "ssl_gc_referee_message.pb.h"

namespace ubersim::testing {

std::string StopRefereeDatagram(const std::string& yellow, const std::string& blue, std::int64_t stage_time_left_us) {
  Referee r;
  r.set_packet_timestamp(1);
  r.set_stage(Referee::NORMAL_FIRST_HALF);
  r.set_stage_time_left(stage_time_left_us);
  r.set_command(Referee::STOP);
  r.set_command_counter(3);
  r.set_command_timestamp(1);
  r.set_next_command(Referee::DIRECT_FREE_YELLOW);
  r.mutable_designated_position()->set_x(-1200.0f);
  r.mutable_designated_position()->set_y(800.0f);
  for (Referee::TeamInfo* t : {r.mutable_yellow(), r.mutable_blue()}) {
    const bool is_yellow = t == r.mutable_yellow();
    t->set_name(is_yellow ? yellow : blue);
    t->set_score(is_yellow ? 1 : 0);
    t->set_red_cards(0);
    t->set_yellow_cards(0);
    t->set_timeouts(4);
    t->set_timeout_time(300'000'000);
    t->set_goalkeeper(0);
  }
  r.mutable_blue()->set_yellow_cards(1);
  r.mutable_blue()->add_yellow_card_times(45'000'000);
  GameEvent* e = r.add_game_events();
  e->set_type(GameEvent::BALL_LEFT_FIELD_TOUCH_LINE);
  e->mutable_ball_left_field_touch_line()->set_by_team(BLUE);
  return r.SerializeAsString();
}

}  // namespace ubersim::testing
