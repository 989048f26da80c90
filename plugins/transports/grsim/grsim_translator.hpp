// SPDX-License-Identifier: Apache-2.0
// The grSim protocol's meaning in ÜberSim's terms: packets to kernel events, and robot status back.
#pragma once

#include <map>
#include <string>
#include <utility>
#include <vector>

#include <ubersim/events.hpp>
#include <ubersim/world_state.hpp>

#include "grsim_packet.pb.h"

namespace ubersim::grsim {

/// What the translator needs of the world, from the latest snapshot (SI).
struct WorldView {
  bool known = false;              ///< false before the first snapshot: robot ids are not checked
  std::vector<RobotId> robots;     ///< the robots in the world
  Vec3 ball_position = Vec3::Zero();  ///< m
  Vec3 ball_velocity = Vec3::Zero();  ///< m/s
  double ball_radius = 0.0215;     ///< m
  double half_length = 0;          ///< half the carpet along x, m (0: positions not checked)
  double half_width = 0;           ///< half the carpet along y, m
};

/// Turns grSim packets into position and command events. Each robot command and each replacement
/// is checked on its own (commands: a known robot of that team; replacements: ids 0..15, a robot
/// not in the world comes on; finite values, on the carpet): a bad one is left out with a reason,
/// the others still apply. Remembers each robot's spinner, so a dribbler
/// is only told when it changes, and each robot's last kick elevation.
class Translator {
 public:
  /// `spinner_speed`: dribbler speed for spinner = true, rad/s.
  explicit Translator(double spinner_speed) : spinner_speed_(spinner_speed) {}
  /// Appends the events of every valid entry of `packet`, and one reason per rejected entry.
  void Translate(const grSim_Packet& packet, const WorldView& world, std::vector<Event>& events,
                 std::vector<std::string>& rejects);
  /// Elevation of the last kick asked of `robot`, rad (0: flat, or none asked).
  double LastKickAngle(const RobotId& robot) const;
  /// Forgets the spinners (after a world reset every dribbler is off again).
  void ForgetSpinners() { spinner_.clear(); }

 private:
  void Command(const grSim_Robot_Command& c, Team team, const WorldView& world,
               std::vector<Event>& events, std::vector<std::string>& rejects);
  void Ball(const grSim_BallReplacement& b, const WorldView& world, std::vector<Event>& events,
            std::vector<std::string>& rejects);
  void Robot(const grSim_RobotReplacement& r, const WorldView& world, std::vector<Event>& events,
             std::vector<std::string>& rejects);

  double spinner_speed_;
  std::map<std::pair<int, int>, bool> spinner_;
  std::map<std::pair<int, int>, double> kick_angle_;
};

/// Robot status as grSim reports it: infrared (the dribbler touches the ball) and whether the
/// robot kicked flat or chipped since the last report. Reports only robots whose status changed
/// since the last report; the first report has every robot.
class StatusTracker {
 public:
  /// From each snapshot. A kicker that stops being ready has fired; `translator` tells flat from chip.
  void Observe(const std::vector<RobotState>& robots, const Translator& translator);
  /// The changed robots, blue and yellow; what it returns counts as reported.
  std::pair<Robots_Status, Robots_Status> TakeChanged();

 private:
  struct Entry {
    RobotId id;
    bool infrared = false;
    bool kicker_ready = false;
    bool flat_pending = false;  // kicked since the last report
    bool chip_pending = false;
    bool reported = false;
    bool last_infrared = false, last_flat = false, last_chip = false;
  };
  std::vector<Entry> entries_;
};

}  // namespace ubersim::grsim
