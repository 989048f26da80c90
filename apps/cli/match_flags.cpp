// SPDX-License-Identifier: Apache-2.0
#include "match_flags.hpp"

#include "exit_codes.hpp"

namespace ubersim::cli {

namespace po = boost::program_options;

void MatchFlags::AddTo(po::options_description& desc) {
  desc.add_options()
      ("referee", po::value<std::string>(&referee)->default_value("none"),
       "builtin: ÜberSim referees the match and publishes Referee messages on 224.5.23.1:10003; gc: ÜberSim is the "
       "autoreferee of a game controller in CI mode (--game-controller) and publishes its messages; none (docs/match.md)")
      ("game-controller", po::value<std::string>(&game_controller)->default_value("localhost:10009"),
       "HOST:PORT of ssl-game-controller -timeAcquisitionMode ci (with --referee gc)")
      ("tracker", po::bool_switch(&tracker), "publish tracked vision (TrackerWrapperPacket) from the simulated truth on 224.5.23.2:10010")
      ("tracker-noise", po::bool_switch(&tracker_noise),
       "tracked positions carry the world's vision noise (perception: σ of positions and orientations), seeded by the world")
      ("referee-port", po::value<int>(&referee_port)->default_value(10003), "port of the Referee messages (group 224.5.23.1)")
      ("tracker-port", po::value<int>(&tracker_port)->default_value(10010), "port of the tracked frames (group 224.5.23.2)")
      ("record", po::value<std::string>(&record),
       "write every vision, referee and tracker message to FILE in the league's log format (.gz: compressed)")
      ("half-duration", po::value<double>(&half_duration)->default_value(300.0), "playing time per half, s")
      ("half-time-break", po::value<double>(&half_time_break)->default_value(300.0), "half-time break, s")
      ("first-kickoff", po::value<std::string>(&first_kickoff)->default_value("yellow"), "team that kicks off first: yellow or blue")
      ("yellow-name", po::value<std::string>(&yellow_name)->default_value("Yellow"), "yellow team's name")
      ("blue-name", po::value<std::string>(&blue_name)->default_value("Blue"), "blue team's name")
      ("yellow-keeper", po::value<int>(&yellow_keeper)->default_value(0), "yellow goalkeeper's id")
      ("blue-keeper", po::value<int>(&blue_keeper)->default_value(0), "blue goalkeeper's id")
      ("placement", po::value<std::string>(&placement)->default_value("auto"),
       "who places the ball for free kicks: auto (the team; the simulator when the team makes no progress) or simulator");
}

void MatchFlags::FromWorld(const ParamView& m, const po::variables_map& vm) {
  if (!m.IsObject()) return;  // no match: block
  const auto unset = [&](const char* option) { return vm.count(option) == 0 || vm[option].defaulted(); };
  if (unset("referee")) referee = m.GetString("referee", referee);
  if (unset("game-controller")) game_controller = m.GetString("game_controller", game_controller);
  if (unset("tracker")) tracker = m.GetBool("tracker", tracker);
  if (unset("tracker-noise")) tracker_noise = m.GetBool("tracker_noise", tracker_noise);
  if (unset("half-duration")) half_duration = m.GetDouble("half_duration", half_duration);
  if (unset("half-time-break")) half_time_break = m.GetDouble("half_time_break", half_time_break);
  if (unset("first-kickoff")) first_kickoff = m.GetString("first_kickoff", first_kickoff);
  if (unset("placement")) placement = m.GetString("placement", placement);
  if (m.Has("yellow")) {
    if (unset("yellow-name")) yellow_name = m["yellow"].GetString("name", yellow_name);
    if (unset("yellow-keeper")) yellow_keeper = static_cast<int>(m["yellow"].GetInt("keeper", yellow_keeper));
  }
  if (m.Has("blue")) {
    if (unset("blue-name")) blue_name = m["blue"].GetString("name", blue_name);
    if (unset("blue-keeper")) blue_keeper = static_cast<int>(m["blue"].GetInt("keeper", blue_keeper));
  }
}

match::MatchOptions MatchFlags::Options(const kernel::WorldModel& model, bool local_only,
                                        std::unique_ptr<sslog::LogWriter>& writer) const {
  match::MatchOptions o;
  if (referee != "none" && referee != "builtin" && referee != "gc") {
    throw UsageError("--referee " + referee + ": builtin, gc or none");
  }
  if (first_kickoff != "yellow" && first_kickoff != "blue") throw UsageError("--first-kickoff " + first_kickoff + ": yellow or blue");
  if (placement != "auto" && placement != "simulator") throw UsageError("--placement " + placement + ": auto or simulator");
  if (!(half_duration > 0) || !(half_time_break >= 0)) throw UsageError("--half-duration must be > 0 and --half-time-break >= 0");
  if (referee == "builtin" || referee == "gc") {
    match::RefereeConfig c;
    // Div B's field is 9 × 6 m: its robot limit and time limits follow.
    c.division = model.field->geometry.field_length < 10.5 ? match::Division::kB : match::Division::kA;
    c.half_duration = half_duration;
    c.half_time_break = half_time_break;
    c.first_kickoff = first_kickoff == "blue" ? Team::kBlue : Team::kYellow;
    c.yellow_name = yellow_name;
    c.blue_name = blue_name;
    c.yellow_keeper = yellow_keeper;
    c.blue_keeper = blue_keeper;
    c.yellow_can_place = c.blue_can_place = placement == "auto";
    o.referee = c;
    if (referee == "gc") o.game_controller = game_controller;
  }
  for (int port : {referee_port, tracker_port}) {
    if (port < 1 || port > 65535) throw UsageError("--referee-port and --tracker-port take 1..65535, not " + std::to_string(port));
  }
  o.referee_port = static_cast<std::uint16_t>(referee_port);
  o.tracker_port = static_cast<std::uint16_t>(tracker_port);
  o.tracker = tracker || tracker_noise;
  o.tracker_noise = tracker_noise;
  o.local_only = local_only;
  if (!record.empty()) {
    writer = std::make_unique<sslog::LogWriter>(record);
    sslog::LogWriter* w = writer.get();
    o.recorder = [w](std::int64_t unix_ns, match::WireMessage type, const std::string& bytes) {
      w->Write(unix_ns, static_cast<std::int32_t>(type), bytes);
    };
  }
  return o;
}

}  // namespace ubersim::cli
