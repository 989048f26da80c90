// SPDX-License-Identifier: Apache-2.0
// Random play: the seeded commands bench, batch, soak and the pinned-hash test drive worlds with.
#pragma once

#include <cstdint>
#include <optional>
#include <random>
#include <vector>

#include "ubersim/kernel/world.hpp"

namespace ubersim::apps {

using kernel::World;

/// Drives every robot of a world with seeded random commands (waypoints across the field at up
/// to 3 m/s, turning, dribbling, kicking) at a 100 Hz radio rate, and keeps the ball in play:
/// the same events a team's software sends, through the same kernel paths.
class RandomPlay {
 public:
  /// Plays in `world` with this seed: every robot, or only `team`'s (the ball is kept in play
  /// either way).
  RandomPlay(World& world, std::uint64_t seed, std::optional<Team> team = std::nullopt);
  /// Posts the commands due before the next step; true when it moved the ball.
  bool BeforeStep();

 private:
  struct Player {
    RobotId id;
    std::size_t index = 0;  // in the ground truth's robots
    bool dribbler = false, kicker = false;
    double target_x = 0, target_y = 0, speed = 1, turn = 0;
    std::int64_t next_target_ns = 0;
  };
  void NewTarget(Player& p, std::int64_t now_ns);
  // A random point on the field clear of every robot in `s`, for a ball that left it (a ball put
  // inside a robot's shell could not get out).
  Vec3 FreeBallPoint(const WorldSnapshot& s);

  World& world_;
  std::mt19937_64 rng_;
  std::vector<Player> players_;
  double half_length_ = 4.5, half_width_ = 3.0;
  std::int64_t next_radio_ns_ = 0;
  std::int64_t next_ball_ns_ = 0;
};

}  // namespace ubersim::apps
