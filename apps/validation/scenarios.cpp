// SPDX-License-Identifier: Apache-2.0
// The list of validation scenarios, in the order the report shows them.
#include "ubersim/validation/scenarios.hpp"

#include <stdexcept>

#include "ball_scenarios.hpp"
#include "paper_scenarios.hpp"
#include "parts_scenarios.hpp"
#include "robot_scenarios.hpp"

namespace ubersim::validation {

const std::vector<Scenario>& AllScenarios() {
  using namespace detail;
  static const std::vector<Scenario> kAll = {
      {"ball_roll_2", "Ball rolled at 2 m/s", [](const Environment& e) { return BallRoll(e, 2.0); }},
      {"ball_roll_5", "Ball rolled at 5 m/s", [](const Environment& e) { return BallRoll(e, 5.0); }},
      {"chip_flight", "Chip flight and bounces", ChipFlight},
      {"no_tunnelling", "1000 shots at 6.5 m/s", [](const Environment& e) { return NoTunnelling(e, 1000); }},
      {"omni_steady_velocity", "Omni robot steady velocities",
       [](const Environment& e) { return OmniSteadyVelocity(e); }},
      {"omni_acceleration", "Omni robot acceleration", [](const Environment& e) { return OmniAcceleration(e); }},
      {"omni_force_steady_velocity", "Omni robot on the omni_force drive: steady velocities",
       [](const Environment& e) { return OmniSteadyVelocity(e, kForceOmni); }},
      {"omni_force_acceleration", "Omni robot on the omni_force drive: acceleration",
       [](const Environment& e) { return OmniAcceleration(e, kForceOmni); }},
      {"mecanum_steady_velocity", "Mecanum robot steady velocities",
       [](const Environment& e) { return OmniSteadyVelocity(e, kMecanum); }},
      {"mecanum_acceleration", "Mecanum robot acceleration", [](const Environment& e) { return OmniAcceleration(e, kMecanum); }},
      {"mecanum_grip_limit", "Mecanum robot: grip-limited speed-up", MecanumGripLimit},
      {"kicker_speeds", "Kicker: clamped flat kick, chip angle", [](const Environment& e) { return KickerSpeeds(e); }},
      {"dribbler_hold", "Dribbler: hold while driving and turning",
       [](const Environment& e) { return DribblerHold(e); }},
      {"omni_force_kicker_speeds", "Kicker on the omni_force robot: clamped flat kick, chip angle",
       [](const Environment& e) { return KickerSpeeds(e, kForceOmni.file, "omni_force_kicker_speeds"); }},
      {"omni_force_dribbler_hold", "Dribbler on the omni_force robot: hold while driving and turning",
       [](const Environment& e) { return DribblerHold(e, kForceOmni.file, "omni_force_dribbler_hold"); }},
      {"paper_acceleration", "2003 paper: straight-line acceleration at 2 m/s²", PaperAcceleration},
      {"paper_figure_eight", "2003 paper: figure-8 at 0.8 m/s", PaperFigureEight},
  };
  return kAll;
}

std::vector<Scenario> RobotScenarios(const Environment& env, const std::filesystem::path& robot_file) {
  using namespace detail;
  const kernel::ModelLoader loader(env.schema_dir, [&env](PluginKind kind, const std::string& id) {
    return env.registry->Find(kind, id).schema_json;
  });
  const auto robot = loader.LoadRobot(robot_file);
  const OmniModel m = RobotUnderTest(*robot, robot_file);
  std::vector<Scenario> out = {
      {m.drive + "_steady_velocity", m.name + ": steady speed follows the command",
       [m](const Environment& e) { return OmniSteadyVelocity(e, m); }},
      {m.drive + "_acceleration", m.name + ": speed-up follows its acceleration limit",
       [m](const Environment& e) { return OmniAcceleration(e, m); }}};
  if (robot->kicker) {
    out.push_back({m.drive + "_kicker_speeds", m.name + ": kicker flat limit and chip angle",
                   [m](const Environment& e) { return KickerSpeeds(e, m.file, m.drive + "_kicker_speeds"); }});
  }
  if (robot->dribbler) {
    out.push_back({m.drive + "_dribbler_hold", m.name + ": dribbler holds the ball while turning and driving",
                   [m](const Environment& e) { return DribblerHold(e, m.file, m.drive + "_dribbler_hold"); }});
  }
  return out;
}

const Scenario& FindScenario(const std::string& id) {
  std::string ids;
  for (const Scenario& s : AllScenarios()) {
    if (s.id == id) return s;
    ids += (ids.empty() ? "" : ", ") + s.id;
  }
  throw std::out_of_range("no validation scenario '" + id + "' (there are: " + ids + ")");
}

}  // namespace ubersim::validation
