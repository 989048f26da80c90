// SPDX-License-Identifier: Apache-2.0
// A stand-in for ssl-game-controller in CI mode, written from ssl-match-protocols.md §1 (the real
// one is a Go program that cannot be fetched here): a TCP server on loopback that reads
// varint-delimited CiInputs, keeps every one, and answers each with one CiOutput. Its state machine
// is the part of the game controller a match needs: its clock is the inputs' time stamps; changes
// set commands and stages; the autoreferee's events stop play and set the next command and the
// placement position; it auto-continues 2 s after STOP (placement first when the ball is away);
// a possible goal halts until ACCEPT_GOAL scores it.
#pragma once

#include <cmath>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <boost/asio.hpp>

#include "../common/referee_messages.hpp"
#include "ssl_gc_ci.pb.h"
#include "transport_common/delimited.hpp"

namespace ubersim::testing {

class StandinGameController {
 public:
  StandinGameController() : acceptor_(io_, {boost::asio::ip::make_address("127.0.0.1"), 0}) {
    referee_ = HaltedReferee(0);
    referee_.set_stage_time_left(300'000'000);
    for (Referee::TeamInfo* t : {referee_.mutable_yellow(), referee_.mutable_blue()}) t->set_max_allowed_bots(6);
    referee_.set_next_command(Referee::PREPARE_KICKOFF_YELLOW);
    thread_ = std::thread([this] { Serve(); });
  }
  ~StandinGameController() {
    io_.stop();
    boost::system::error_code ignored;
    acceptor_.close(ignored);
    if (thread_.joinable()) thread_.join();
  }

  /// Where it listens: "127.0.0.1:PORT".
  std::string Address() const { return "127.0.0.1:" + std::to_string(acceptor_.local_endpoint().port()); }
  /// Every input received so far.
  std::vector<CiInput> Inputs() const {
    std::lock_guard lock(mutex_);
    return inputs_;
  }
  /// Every message sent so far.
  std::vector<Referee> Outputs() const {
    std::lock_guard lock(mutex_);
    return outputs_;
  }

 private:
  void Serve() {
    boost::system::error_code error;
    boost::asio::ip::tcp::socket socket(io_);
    acceptor_.accept(socket, error);
    if (error) return;
    transport::DelimitedDecoder decoder(1 << 20);
    std::vector<char> buffer(65536);
    for (;;) {
      const std::size_t n = socket.read_some(boost::asio::buffer(buffer), error);
      if (error) return;
      decoder.Append(std::string_view(buffer.data(), n));
      std::string message, why;
      while (decoder.Next(message, why) == transport::DelimitedDecoder::Status::kMessage) {
        CiInput input;
        if (!input.ParseFromString(message)) continue;
        CiOutput output;
        {
          std::lock_guard lock(mutex_);
          inputs_.push_back(input);
          Apply(input);
          *output.mutable_referee_msg() = referee_;
          outputs_.push_back(referee_);
        }
        boost::asio::write(socket, boost::asio::buffer(transport::EncodeDelimited(output.SerializeAsString())), error);
        if (error) return;
      }
    }
  }

  void Command(Referee::Command c) {
    referee_.set_command(c);
    referee_.set_command_counter(referee_.command_counter() + 1);
    t_command_ = now_;
    if (c == Referee::NORMAL_START || c == Referee::FORCE_START || c == Referee::DIRECT_FREE_BLUE ||
        c == Referee::DIRECT_FREE_YELLOW) {
      referee_.clear_designated_position();
      referee_.clear_next_command();
      referee_.clear_game_events();
    }
  }
  void StopFor(Referee::Command next, float x_mm, float y_mm) {
    referee_.set_next_command(next);
    referee_.mutable_designated_position()->set_x(x_mm);
    referee_.mutable_designated_position()->set_y(y_mm);
    Command(Referee::STOP);
  }

  void Apply(const CiInput& in) {
    if (in.has_timestamp()) now_ = in.timestamp();
    if (in.has_tracker_packet() && in.tracker_packet().tracked_frame().balls_size() > 0) {
      const auto& p = in.tracker_packet().tracked_frame().balls(0).pos();
      ball_x_ = p.x() * 1000;
      ball_y_ = p.y() * 1000;
    }
    for (const Input& i : in.api_inputs()) {
      if (i.has_continue_action() && i.continue_action().type() == ContinueAction::ACCEPT_GOAL) {
        const bool blue = i.continue_action().for_team() == ::BLUE;
        auto* team = blue ? referee_.mutable_blue() : referee_.mutable_yellow();
        team->set_score(team->score() + 1);
        *referee_.add_game_events() = GameEvent();
        referee_.mutable_game_events()->rbegin()->set_type(GameEvent::GOAL);
        referee_.set_next_command(blue ? Referee::PREPARE_KICKOFF_YELLOW : Referee::PREPARE_KICKOFF_BLUE);
        referee_.mutable_designated_position()->set_x(0);
        referee_.mutable_designated_position()->set_y(0);
        referee_.set_command_counter(referee_.command_counter() + 1);  // HALT stays
      }
      if (!i.has_change()) continue;
      const Change& c = i.change();
      if (c.has_new_command_change() && c.new_command_change().command().type() == ::Command::STOP) {
        Command(Referee::STOP);
      }
      if (c.has_change_stage_change()) {
        referee_.set_stage(c.change_stage_change().new_stage());
        Command(Referee::HALT);
      }
      if (c.has_add_game_event_change()) {
        const GameEvent& e = c.add_game_event_change().game_event();
        *referee_.add_game_events() = e;
        if (e.type() == GameEvent::BALL_LEFT_FIELD_TOUCH_LINE) {
          const bool yellow_touched = e.ball_left_field_touch_line().by_team() == ::YELLOW;
          const float y = e.ball_left_field_touch_line().location().y();
          const float x = e.ball_left_field_touch_line().location().x();
          StopFor(yellow_touched ? Referee::DIRECT_FREE_BLUE : Referee::DIRECT_FREE_YELLOW, x * 1000,
                  (y > 0 ? y - 0.2f : y + 0.2f) * 1000);
        }
        if (e.type() == GameEvent::PLACEMENT_SUCCEEDED) Command(Referee::STOP);
        if (e.type() == GameEvent::POSSIBLE_GOAL) Command(Referee::HALT);
      }
    }
    // Auto-continue, 2 s after STOP (or PREPARE_KICKOFF).
    const bool waited = now_ - t_command_ >= 2'000'000'000LL;
    const Referee::Command cmd = referee_.command();
    if (cmd == Referee::STOP && referee_.has_next_command() && waited) {
      const Referee::Command next = referee_.next_command();
      const bool direct = next == Referee::DIRECT_FREE_BLUE || next == Referee::DIRECT_FREE_YELLOW;
      const float dx = ball_x_ - referee_.designated_position().x(), dy = ball_y_ - referee_.designated_position().y();
      if (direct && std::hypot(dx, dy) > 150.0f) {
        Command(next == Referee::DIRECT_FREE_BLUE ? Referee::BALL_PLACEMENT_BLUE : Referee::BALL_PLACEMENT_YELLOW);
      } else if (next == Referee::PREPARE_KICKOFF_BLUE || next == Referee::PREPARE_KICKOFF_YELLOW) {
        if (std::hypot(ball_x_, ball_y_) < 150.0f) {
          referee_.set_next_command(Referee::NORMAL_START);
          Command(next);
        }
      } else {
        Command(next);
      }
    } else if ((cmd == Referee::PREPARE_KICKOFF_BLUE || cmd == Referee::PREPARE_KICKOFF_YELLOW) && waited) {
      if (referee_.stage() == Referee::NORMAL_FIRST_HALF_PRE) referee_.set_stage(Referee::NORMAL_FIRST_HALF);
      Command(Referee::NORMAL_START);
    }
  }

  boost::asio::io_context io_;
  boost::asio::ip::tcp::acceptor acceptor_;
  std::thread thread_;
  mutable std::mutex mutex_;
  std::vector<CiInput> inputs_;
  std::vector<Referee> outputs_;
  Referee referee_;
  std::int64_t now_ = 0, t_command_ = 0;
  float ball_x_ = 0, ball_y_ = 0;
};

}  // namespace ubersim::testing
