// SPDX-License-Identifier: Apache-2.0
// Robots meeting as on a real field: pushing each other, crashing head-on at match speeds, and
// one teleported onto another. At both physics profiles they stay upright, meet at their
// surfaces (the state check's shell penetration), and a teleported robot is pushed out, not
// thrown. The fast profile's 5 ms step closes 30 mm at 6 m/s before a contact exists: its
// speculative robot contacts, both contact levels of two shells and more iterations for robots
// in contact are what hold these (docs/performance.md, reference/physics.md §3d).
#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "ubersim/kernel/logging.hpp"
#include "ubersim/kernel/model.hpp"
#include "ubersim/kernel/state_check.hpp"
#include "ubersim/kernel/world.hpp"

#include "../common/sanitizer.hpp"

namespace ubersim::kernel {
namespace {

// How far a robot leans from upright, rad.
double Tilt(const RobotState& r) { return std::acos(std::clamp((r.pose.orientation * Vec3::UnitZ()).z(), -1.0, 1.0)); }

// What happened to the two robots over a run.
struct Outcome {
  double deepest = 0;    // m, shell inside shell (the state check's measure)
  double most_tilt = 0;  // rad, either robot from upright
  double end_tilt = 0;   // rad, at the end
  double fastest = 0;    // m/s, either chassis
};

struct TwoRobots {
  std::ostringstream text;
  StreamLog log{text, LogLevel::kWarning};
  PluginRegistry registry{{UBERSIM_PLUGIN_BUILD_DIR}};
  std::unique_ptr<World> world;
  double dt = 0.001;

  // Blue facing +x at (xb, 0), yellow facing -x at (xy, y), on the Div B field.
  TwoRobots(const std::string& profile, const std::string& robot, double xb, double xy, double y = 0.0,
            PhysicsOverrides o = {}, double yaw_blue = 0.0, double yaw_yellow = M_PI) {
    const ModelLoader loader(ModelLoader::DefaultSchemaDir(),
                             [this](PluginKind k, const std::string& id) { return registry.Find(k, id).schema_json; });
    WorldModel model = loader.LoadWorld(UBERSIM_SOURCE_DIR "/models/worlds/div-b.yaml");
    o.profile = profile;
    o.ApplyTo(model.physics);
    dt = model.physics.step;
    model.robots.clear();
    const auto r = loader.LoadRobot(UBERSIM_SOURCE_DIR "/models/robots/" + robot);
    model.robots.push_back(RobotPlacement{{Team::kBlue, 0}, r, xb, 0.0, yaw_blue, true});
    model.robots.push_back(RobotPlacement{{Team::kYellow, 0}, r, xy, y, yaw_yellow, true});
    model.ball_start = Vec3(3.5, 2.5, 0);  // out of the way
    model.radio = RadioModel{};
    world = std::make_unique<World>(model, registry, log, false);
  }

  // Both drive forward at `speed` (commands at 100 Hz) for `seconds`, then brake for 1 s.
  Outcome Drive(double speed, double seconds) {
    Outcome out;
    const int every = std::max(1, static_cast<int>(std::lround(0.01 / dt)));
    const int driving = static_cast<int>(std::lround(seconds / dt));
    const int total = driving + static_cast<int>(std::lround(1.0 / dt));
    StateCheckOptions overlap;
    overlap.finite = overlap.speed = overlap.carpet = overlap.walls = false;
    overlap.limits.robot_penetration = 0.0;  // every depth, to take the deepest
    for (int i = 0; i < total; ++i) {
      if (i % every == 0 && i < driving) {
        for (Team t : {Team::kBlue, Team::kYellow}) {
          world->events().Post(CommandEvent{{t, 0}, LocalVelocityCommand{speed, 0, 0}, {}, {}});
        }
      }
      world->Step();
      for (const StateViolation& v : CheckState(*world, overlap)) {
        if (v.other && v.other->kind == StateObject::Kind::kRobot) out.deepest = std::max(out.deepest, v.value);
      }
      const WorldSnapshot s = world->GroundTruth();
      out.end_tilt = 0;
      for (const RobotState& r : s.robots) {
        const double tilt = Tilt(r);
        out.most_tilt = std::max(out.most_tilt, tilt);
        out.end_tilt = std::max(out.end_tilt, tilt);
        out.fastest = std::max(out.fastest, r.twist.linear.norm());
      }
    }
    return out;
  }
};

constexpr double kDeg = M_PI / 180.0;

// A robot as it was at a moment of a run: where, heading, velocity and turn (m, rad, m/s, rad/s).
struct Moving {
  Team team;
  double x, y, yaw, vx, vy, spin;
};

// Puts each robot down as it was, moving.
void PutDown(TwoRobots& w, const std::vector<Moving>& robots) {
  for (const Moving& m : robots) {
    PositionEvent e;
    e.target = Target::Robot({m.team, 0});
    e.position = Vec3(m.x, m.y, 0);
    e.yaw = m.yaw;
    e.velocity = Vec3(m.vx, m.vy, 0);
    e.angular_velocity = Vec3(0, 0, m.spin);
    w.world->events().Post(e);
  }
  w.world->ProcessEvents();
}

// Tells each robot to keep the velocity it was put down with, in its own frame.
void KeepMoving(TwoRobots& w, const std::vector<Moving>& robots) {
  for (const Moving& m : robots) {
    const double c = std::cos(m.yaw), s = std::sin(m.yaw);
    w.world->events().Post(
        CommandEvent{{m.team, 0}, LocalVelocityCommand{c * m.vx + s * m.vy, -s * m.vx + c * m.vy, m.spin}, {}, {}});
  }
}

// Deepest shell-in-shell a crash may leave: at precise a 6 m/s crash closes 6 mm in the step
// before its contact exists (plus the 0.5 mm contact layer); at fast the speculative contacts
// meet the shells at their surfaces.
double CrashDepthLimit(const std::string& profile) { return profile == "precise" ? 0.0065 : 0.002; }
// How far a robot may still lean once a crash is over: back on its wheels (a wheel-body robot's
// hinges sagged 1.5-2° at rest at two solver iterations; contact wheels stand level).
constexpr double kRestingTilt = 3 * kDeg;

// What a strike did over `seconds`: the robots keep their velocities for its first 0.1 s.
struct Aftermath {
  double deepest = 0;       // m, shell inside shell
  double most_tilt = 0;     // rad, either robot from upright
  double fastest_roll = 0;  // rad/s, either robot about a horizontal axis
};
Aftermath Strike(TwoRobots& w, const std::vector<Moving>& robots, double seconds) {
  PutDown(w, robots);
  StateCheckOptions overlap;
  overlap.finite = overlap.speed = overlap.carpet = overlap.walls = false;
  overlap.limits.robot_penetration = 0.0;
  const int every = std::max(1, static_cast<int>(std::lround(0.01 / w.dt)));
  Aftermath out;
  for (int i = 0; i < static_cast<int>(std::lround(seconds / w.dt)); ++i) {
    if (i % every == 0 && i * w.dt < 0.1) KeepMoving(w, robots);
    w.world->Step();
    for (const StateViolation& v : CheckState(*w.world, overlap)) {
      if (v.other && v.other->kind == StateObject::Kind::kRobot) out.deepest = std::max(out.deepest, v.value);
    }
    for (const RobotState& r : w.world->GroundTruth().robots) {
      out.most_tilt = std::max(out.most_tilt, Tilt(r));
      out.fastest_roll = std::max(out.fastest_roll, r.twist.angular.head<2>().norm());
    }
  }
  return out;
}

class RobotCrash : public ::testing::TestWithParam<std::tuple<std::string, std::string>> {};

// Both profiles times both drives, and a test name from each pair ("fast_ssl_omni_2026_yaml").
auto ProfilesAndDrives() {
  return ::testing::Combine(::testing::Values("precise", "fast"),
                            ::testing::Values("ssl-omni-2026.yaml", "ssl-omni-2026-force.yaml"));
}
std::string ProfileAndDriveName(const ::testing::TestParamInfo<std::tuple<std::string, std::string>>& info) {
  std::string name = std::get<0>(info.param) + "_" + std::get<1>(info.param);
  std::replace_if(name.begin(), name.end(), [](char c) { return !std::isalnum(c); }, '_');
  return name;
}

// 3 m/s each, 6 m/s closing: the fastest two robots meet. They stop each other and stay on their
// wheels; at fast, before the fixes, the wheel-body robots sank 18 mm into each other and tipped
// past the upright shells' 5.7° (then met as meshes).
TEST_P(RobotCrash, HeadOnAtSixMetresPerSecondClosingLeavesBothUpright) {
  const auto& [profile, robot] = GetParam();
  TwoRobots w(profile, robot, -1.5, 1.5);
  const Outcome o = w.Drive(3.0, 1.8);
  EXPECT_LT(o.deepest, CrashDepthLimit(profile)) << "shell inside shell, m";
  EXPECT_LT(o.most_tilt, 10 * kDeg) << "most tilt, rad";
  EXPECT_LT(o.end_tilt, kRestingTilt) << "back on their wheels";
}

// Two robots pushing nose to nose at full drive for 3 s: the push does not sink them into each
// other (the soak found 15-26 mm at fast).
TEST_P(RobotCrash, PushingNoseToNoseDoesNotSinkIn) {
  const auto& [profile, robot] = GetParam();
  TwoRobots w(profile, robot, -0.1, 0.1);
  const Outcome o = w.Drive(1.5, 3.0);
  EXPECT_LT(o.deepest, 0.003);
  EXPECT_LT(o.most_tilt, 6 * kDeg);
}

// A robot put down onto another (a client's teleport) is pushed out at no more than the
// correcting velocity (3 m/s): it is not thrown across the field or over the walls.
TEST_P(RobotCrash, ARobotTeleportedOntoAnotherIsSeparatedNotThrown) {
  const auto& [profile, robot] = GetParam();
  TwoRobots w(profile, robot, 0.0, 0.05, 0.03);  // 5 cm apart: deep inside each other
  const Outcome o = w.Drive(0.0, 0.0);
  EXPECT_LT(o.fastest, 3.5) << "m/s";
  EXPECT_LT(o.most_tilt, 10 * kDeg) << "most tilt, rad";
  EXPECT_LT(o.end_tilt, kRestingTilt);
  const WorldSnapshot s = w.world->GroundTruth();
  const Vec3 a = s.robots[0].pose.position, b = s.robots[1].pose.position;
  EXPECT_GT(std::hypot(a.x() - b.x(), a.y() - b.y()), 0.135) << "pushed apart";
  EXPECT_LT(std::hypot(a.x(), a.y()), 1.0) << "not thrown";
}

// A robot put down moving (a client's teleport with a velocity) drives on from there: its wheels
// roll with it and its speed loop starts from that velocity (Drive::Placed), so with no command
// it brakes at its servo's 6 m/s². Before, its wheels kept their old spin and skidded the chassis
// down at the carpet's full friction (0.8 g): a robot thrown in at 2.5 m/s tipped forward over
// its front wheels, and the soak found it leaning 20° and more.
TEST_P(RobotCrash, ARobotPutDownMovingDrivesOnFromThatVelocity) {
  const auto& [profile, robot] = GetParam();
  TwoRobots w(profile, robot, -1.0, 1.5);
  const auto forward = [&] {
    w.world->events().Post(CommandEvent{{Team::kBlue, 0}, LocalVelocityCommand{1.0, 0, 0}, {}, {}});
  };
  // Driving forward at 1 m/s, then put down elsewhere moving backward-left at 1.8 m/s.
  const int every = std::max(1, static_cast<int>(std::lround(0.01 / w.dt)));
  for (int i = 0; i < static_cast<int>(std::lround(1.0 / w.dt)); ++i) {
    if (i % every == 0) forward();
    w.world->Step();
  }
  PositionEvent e;
  e.target = Target::Robot({Team::kBlue, 0});
  e.position = Vec3(-1.0, 0.5, 0.0);
  e.yaw = 0.5;
  e.velocity = Vec3(-1.5, -1.0, 0.0);
  w.world->events().Post(e);
  w.world->ProcessEvents();
  const RobotState put = w.world->GroundTruth().robots[0];
  ASSERT_TRUE(put.drive);
  // What the wheels say is the velocity it was given, in its own frame.
  const double c = std::cos(0.5), s = std::sin(0.5);
  EXPECT_NEAR(put.drive->local_velocity.linear.x(), c * -1.5 + s * -1.0, 0.01);
  EXPECT_NEAR(put.drive->local_velocity.linear.y(), -s * -1.5 + c * -1.0, 0.01);
  EXPECT_NEAR(put.drive->local_velocity.angular.z(), put.twist.angular.z(), 0.01);  // the turn it had
  // Still told to go forward at 1 m/s: its speed loop brakes from the new velocity at 6 m/s², so
  // the velocity changes by about 0.3 m/s in 0.05 s, and it stays on its wheels.
  const Vec3 v0 = put.twist.linear;
  double most_tilt = 0;
  for (int i = 0; i < static_cast<int>(std::lround(0.05 / w.dt)); ++i) {
    if (i % every == 0) forward();
    w.world->Step();
    const RobotState r = w.world->GroundTruth().robots[0];
    most_tilt = std::max(most_tilt, Tilt(r));
  }
  const double change = (w.world->GroundTruth().robots[0].twist.linear - v0).head<2>().norm();
  EXPECT_LT(change, 0.4) << "m/s in 0.05 s: more than its servo brakes";
  EXPECT_GT(change, 0.1) << "m/s in 0.05 s: it does brake";
  EXPECT_LT(most_tilt, 10 * kDeg);
}

// A ball put against a robot (a client's or the soak's teleport), overlapping its shell, and shot
// at 6.5 m/s straight at the robot's centre bounces off: it is not let into the hollow shell.
TEST_P(RobotCrash, ABallPutAgainstARobotAndShotAtItBouncesOff) {
  const auto& [profile, robot] = GetParam();
  int inside = 0, tries = 0;
  std::string where;
  for (int k = 0; k < 12; ++k) {        // around the robot, every 30°
    for (double overlap : {0.0, 0.5, 0.9, 0.98}) {  // share of the ball's radius in the shell
      TwoRobots w(profile, robot, 0.0, 3.0);
      const double a = k * 30.0 * kDeg;
      const Vec3 out(std::cos(a), std::sin(a), 0.0);
      // The shell's reach in that direction: the flat front (0.07 m) or the round 0.09 m.
      const double reach = std::abs(a) < 1e-9 || k == 0 ? 0.07 : 0.09;
      if (k == 0 || k == 1 || k == 11) continue;  // the mouth: the dribbler and kicker take the ball there
      PositionEvent e;
      e.target = Target::Ball();
      e.position = out * (reach + 0.0215 * (1.0 - overlap));
      e.velocity = -6.5 * out;
      w.world->events().Post(e);
      for (int i = 0; i < static_cast<int>(std::lround(0.3 / w.dt)); ++i) w.world->Step();
      StateCheckOptions o;
      o.finite = o.speed = o.carpet = o.walls = o.tilt = false;
      ++tries;
      for (const StateViolation& v : CheckState(*w.world, o)) {
        if (v.object.kind == StateObject::Kind::kBall) {
          ++inside;
          where += " " + std::to_string(k * 30) + "°/" + std::to_string(overlap) + ":" + std::to_string(v.value);
        }
      }
    }
  }
  EXPECT_EQ(inside, 0) << "of " << tries << ":" << where;
}

// A robot told to drive without turning keeps its heading: its firmware's gyro loop
// (GyroRateLoop) holds it. Without the loop the wheel-body robot at fast turned 6-8° in these
// 1.5 s (two solver sweeps leave its four wheels unequally converged, always the same way), and
// a team's robot drove a curve; at precise it turned 0.06°.
class StraightDriving : public ::testing::TestWithParam<std::tuple<std::string, std::string>> {};

TEST_P(StraightDriving, ARobotToldNotToTurnKeepsItsHeading) {
  const auto& [profile, robot] = GetParam();
  for (double forward : {1.0, 2.5}) {
    for (double left : {0.0, 1.0}) {
      TwoRobots w(profile, robot, -2.0, 3.0, 2.0);
      const int every = std::max(1, static_cast<int>(std::lround(0.01 / w.dt)));
      const double yaw0 = w.world->GroundTruth().robots[0].pose.Yaw();
      for (int i = 0; i < static_cast<int>(std::lround(1.5 / w.dt)); ++i) {
        if (i % every == 0) {
          w.world->events().Post(CommandEvent{{Team::kBlue, 0}, LocalVelocityCommand{forward, left, 0}, {}, {}});
        }
        w.world->Step();
      }
      const RobotState r = w.world->GroundTruth().robots[0];
      EXPECT_LT(std::abs(r.pose.Yaw() - yaw0), 1.0 * kDeg) << "forward " << forward << ", left " << left;
      EXPECT_LT(std::abs(r.twist.angular.z()), 0.02) << "rad/s";
      EXPECT_NEAR(r.twist.linear.norm(), std::hypot(forward, left), 0.03) << "m/s";
    }
  }
}

INSTANTIATE_TEST_SUITE_P(BothProfilesBothDrives, StraightDriving,
                         ProfilesAndDrives(), ProfileAndDriveName);

// A ball hitting a robot at an angle, at up to the rules' 6.5 m/s, stays out of its shell: the
// fast-ball sweep takes the whole ball along its path against the shell's solid. With a ray from
// the ball's centre (and the ray's box culling the shell) a ball grazing the flat face's corner
// at 5 ms ended 15-17 mm inside the shell (the soak's limit is 10.7 mm).
TEST_P(RobotCrash, ABallHittingARobotAtAnAngleStaysOutOfItsShell) {
  const auto& [profile, robot] = GetParam();
  double deepest = 0;
  std::string where;
  for (int k = 0; k < 24; ++k) {  // from every 15° around the robot
    for (double offset : {0.0, 0.03, 0.06, 0.08}) {  // m beside the line through its centre
      for (double speed : {4.4, 6.5}) {
        TwoRobots w(profile, robot, 0.0, 3.0);
        const double a = k * 15.0 * kDeg;
        const Vec3 dir(-std::cos(a), -std::sin(a), 0.0);
        PositionEvent e;
        e.target = Target::Ball();
        e.position = -0.3 * dir + offset * Vec3(-dir.y(), dir.x(), 0.0);
        e.velocity = speed * dir;
        w.world->events().Post(e);
        StateCheckOptions o;
        o.finite = o.speed = o.carpet = o.walls = o.tilt = false;
        o.limits.ball_penetration = 0.0;  // every depth, to take the deepest
        for (int i = 0; i < static_cast<int>(std::lround(0.1 / w.dt)); ++i) {
          w.world->Step();
          for (const StateViolation& v : CheckState(*w.world, o)) {
            if (v.object.kind == StateObject::Kind::kBall && v.value > deepest) {
              deepest = v.value;
              where = std::to_string(k * 15) + "°, " + std::to_string(offset) + " m aside, " + std::to_string(speed) + " m/s";
            }
          }
        }
      }
    }
  }
  EXPECT_LT(deepest, 0.008) << "m, from " << where;
}

// A robot put down inside another while moving (a teleport with a velocity) does not strike it
// from inside: the part of its velocity toward the other robot is dropped, the rest kept, and the
// contacts part the two. Before, a robot teleported at 3 m/s into another passed that speed on
// through the overlap, 2 m/s and a 9-19° lean in one step, and the fast soak found the struck
// robot on its side about once in three hours.
TEST_P(RobotCrash, ARobotPutDownInsideAnotherWhileMovingDoesNotStrikeIt) {
  const auto& [profile, robot] = GetParam();
  TwoRobots w(profile, robot, -1.0, 1.5);
  PositionEvent e;
  e.target = Target::Robot({Team::kBlue, 0});
  e.position = Vec3(1.47, 0.0, 0.0);  // 3 cm from yellow's centre
  e.velocity = Vec3(3.0, 0.5, 0.0);   // into yellow, and sideways
  w.world->events().Post(e);
  w.world->ProcessEvents();
  const Vec3 v = w.world->GroundTruth().robots[0].twist.linear;
  EXPECT_NEAR(v.x(), 0.0, 1e-9) << "toward the other robot: dropped";
  EXPECT_NEAR(v.y(), 0.5, 1e-9) << "sideways: kept";
  double most_tilt = 0, fastest = 0;
  for (int i = 0; i < static_cast<int>(std::lround(1.0 / w.dt)); ++i) {
    w.world->Step();
    const RobotState yellow = w.world->GroundTruth().robots[1];
    most_tilt = std::max(most_tilt, Tilt(yellow));
    fastest = std::max(fastest, yellow.twist.linear.norm());
  }
  EXPECT_LT(most_tilt, 10 * kDeg);
  EXPECT_LT(fastest, 1.5) << "m/s: parted, not struck";
  // Put down clear of every robot, it keeps its whole velocity.
  e.position = Vec3(-2.0, 1.0, 0.0);
  w.world->events().Post(e);
  w.world->ProcessEvents();
  const Vec3 clear = w.world->GroundTruth().robots[0].twist.linear;
  EXPECT_NEAR(clear.x(), 3.0, 1e-9);
  EXPECT_NEAR(clear.y(), 0.5, 1e-9);
}

// One robot's flat front strikes another's round back off its centre line, 4.4 m/s closing (the
// fast soak's seed 3 at 1162 s, both robots as they were): they part without sinking into each
// other or spinning up. Before, the contact sat midway between the face's corner and the back,
// off the back's centre line: the push spun the struck robot up to 19 rad/s, the striker to 13,
// and the spin let the solver leave them sinking 3.5 mm a step into each other (17 mm).
TEST_P(RobotCrash, AFrontStrikingARoundBackOffCentreDoesNotSpinThemIntoEachOther) {
  const auto& [profile, robot] = GetParam();
  TwoRobots w(profile, robot, -1.0, 1.5);
  const std::vector<Moving> robots = {{Team::kBlue, -1.6887, 1.3730, 2.318, 1.571, -2.007, -0.92},    // driving backward
                                      {Team::kYellow, -1.6391, 1.1941, 1.802, -0.502, 1.827, 1.25}};  // front first
  PutDown(w, robots);
  StateCheckOptions overlap;
  overlap.finite = overlap.speed = overlap.carpet = overlap.walls = false;
  overlap.limits.robot_penetration = 0.0;
  const int every = std::max(1, static_cast<int>(std::lround(0.01 / w.dt)));
  double deepest = 0, fastest_spin = 0;
  for (int i = 0; i < static_cast<int>(std::lround(0.3 / w.dt)); ++i) {
    if (i % every == 0) KeepMoving(w, robots);
    w.world->Step();
    for (const StateViolation& v : CheckState(*w.world, overlap)) {
      if (v.other && v.other->kind == StateObject::Kind::kRobot) deepest = std::max(deepest, v.value);
    }
    for (const RobotState& r : w.world->GroundTruth().robots) {
      fastest_spin = std::max(fastest_spin, std::abs(r.twist.angular.z()));
    }
  }
  EXPECT_LT(deepest, CrashDepthLimit(profile)) << "shell inside shell, m";
  EXPECT_LT(fastest_spin, 10.0) << "rad/s";
}

// A robot at full speed strikes another crossing its path, 4.1 m/s closing at an angle (the fast
// soak's seed 1 at 950.07 s, both robots as they were): both stay on their wheels.
TEST_P(RobotCrash, AnObliqueStrikeAtFullSpeedLeavesBothOnTheirWheels) {
  const auto& [profile, robot] = GetParam();
  TwoRobots w(profile, robot, -1.0, 1.5);
  const std::vector<Moving> robots = {{Team::kBlue, 0.3580, 0.2966, 0.799, -1.083, -1.072, -1.03},
                                      {Team::kYellow, 0.1463, 0.2519, -0.624, 2.974, -0.084, -0.11}};
  const Aftermath o = Strike(w, robots, 1.0);
  EXPECT_LT(o.deepest, CrashDepthLimit(profile)) << "shell inside shell, m";
  EXPECT_LT(o.most_tilt, 10 * kDeg) << "most tilt, rad";
  EXPECT_LT(o.fastest_roll, 5.0) << "rad/s about a horizontal axis";
}

// A robot at full speed (3 m/s) strikes another crossing at 1.5 m/s, from every side, at every
// heading and off centre: 2-4.5 m/s closing at every angle a match has. Both stay on their
// wheels. Before, 3-4 of these 96 threw a robot onto its side at fast (both drives with wheels),
// 1 at precise with wheel bodies: two robots arriving at a touch within a step had a contact at
// one level of their shells only (the bottom), 3.5 cm below the centres of mass.
TEST_P(RobotCrash, StrikesFromEveryAngleLeaveBothOnTheirWheels) {
  const auto& [profile, robot] = GetParam();
  int tipped = 0, runs = 0;
  double deepest = 0, fastest_roll = 0;
  std::string where;
  for (int striker = 0; striker < 8; ++striker) {     // the striker's direction, every 45°
    for (int crossing = 0; crossing < 4; ++crossing) {  // the struck robot's, every 90°
      for (double aside : {0.0, 0.06, -0.12}) {         // m off the line of the centres
        // The sanitizer pass (ten times slower) strikes on the line of the centres only, where
        // the robots were thrown.
        if (::ubersim::testing::kAddressSanitizer && aside != 0.0) continue;
        TwoRobots w(profile, robot, -1.0, 1.5);
        const double a = striker * 45 * kDeg + 0.2, b = crossing * 90 * kDeg + 0.5;
        const Vec3 vs = 3.0 * Vec3(std::cos(a), std::sin(a), 0), vc = 1.5 * Vec3(std::cos(b), std::sin(b), 0);
        // Put so that the two meet 0.04 s in, `aside` off centre.
        const Vec3 closing = (vs - vc).normalized(), across(-closing.y(), closing.x(), 0);
        const Vec3 meet(0.5, 0.3, 0), struck0 = meet - 0.04 * vc;
        const Vec3 striker0 = meet - 0.04 * vs - 0.18 * closing + aside * across;
        const std::vector<Moving> robots = {
            {Team::kBlue, struck0.x(), struck0.y(), b + 1.0, vc.x(), vc.y(), 0.0},
            {Team::kYellow, striker0.x(), striker0.y(), a - 0.3 * striker, vs.x(), vs.y(), 0.0}};
        const Aftermath o = Strike(w, robots, 0.35);  // thrown robots lie on their sides by then
        ++runs;
        fastest_roll = std::max(fastest_roll, o.fastest_roll);
        deepest = std::max(deepest, o.deepest);
        if (o.most_tilt > 10 * kDeg) {
          ++tipped;
          where += " " + std::to_string(striker * 45) + "°/" + std::to_string(crossing * 90) + "°/" + std::to_string(aside);
        }
      }
    }
  }
  EXPECT_EQ(tipped, 0) << "of " << runs << ", striker°/struck°/aside m:" << where;
  // With both levels' contacts the pair pushes where the shells' faces stay together: the robots
  // rock (3.3-4.7 rad/s measured), not thrown (10-16 rad/s, and onto their sides at fast, while
  // only one level of a just-touching pair had its contact).
  EXPECT_LT(fastest_roll, 6.0) << "rad/s about a horizontal axis";
  // An off-centre strike spins the robots up to 12 rad/s: a flat front's corner then turns 5-6 mm
  // into the other shell within a step, which the contacts at the step's start do not see.
  EXPECT_LT(deepest, 0.008) << "shell inside shell, m";
}

// Where a placed ball lands: as put when it only touches; at the nearest free spot when it
// overlaps a robot's shell or a wall.
Vec3 PutBall(TwoRobots& w, const Vec3& at, const Vec3& velocity = Vec3::Zero()) {
  PositionEvent e;
  e.target = Target::Ball();
  e.position = at;
  e.velocity = velocity;
  w.world->events().Post(e);
  w.world->ProcessEvents();
  return w.world->GroundTruth().ball.pose.position;
}

// The state check's findings of the ball inside a robot or a wall now, described; empty: none.
std::string BallInside(const World& world) {
  StateCheckOptions o;
  o.finite = o.speed = o.carpet = o.tilt = false;
  std::string found;
  for (const StateViolation& v : CheckState(world, o)) {
    if (v.object.kind == StateObject::Kind::kBall) found += v.Describe() + "; ";
  }
  return found;
}

// A ball put 15 mm into the mouth of a robot driving at 2.8 m/s along the wall, 16 mm from it,
// and sent at the robot (the fast soak's seed 1 at 3243.71 s on Div A, moved to Div B's wall).
// Wedged between the wall and the dribbler, its contacts fired it out and spun the robot at
// 13 rad/s onto its side; put where it is free instead, it leaves the robot on its wheels.
TEST_P(RobotCrash, ABallPutIntoARobotsMouthAtTheWallLeavesItOnItsWheels) {
  const auto& [profile, robot] = GetParam();
  constexpr double kShift = 1.8;  // Div A's goal-line wall at x = -6.6, Div B's at -4.8
  for (double speed : {0.0, 2.0, 6.5}) {
    TwoRobots w(profile, robot, 1.0, 2.0);
    const std::vector<Moving> robots = {{Team::kYellow, -6.4912 + kShift, 0.6218, -2.807, -2.195, 1.730, 1.56}};
    PutDown(w, robots);
    const Vec3 ball(-6.5761 + kShift, 0.6469, 0.0215), at(-6.4912 + kShift, 0.6218, 0.0);
    const Vec3 placed = PutBall(w, ball, speed * Vec3(at.x() - ball.x(), at.y() - ball.y(), 0).normalized());
    // Where it went: out of the shell and the wall, within a few centimetres of where it was put.
    EXPECT_LT((placed - ball).norm(), 0.06) << speed << " m/s: moved " << (placed - ball).norm() << " m";
    EXPECT_EQ(BallInside(*w.world), "") << speed << " m/s, as put";
    double most_tilt = 0;
    const int every = std::max(1, static_cast<int>(std::lround(0.01 / w.dt)));
    for (int i = 0; i < static_cast<int>(std::lround(0.5 / w.dt)); ++i) {
      if (i % every == 0 && i * w.dt < 0.2) KeepMoving(w, robots);
      w.world->Step();
      for (const RobotState& r : w.world->GroundTruth().robots) {
        most_tilt = std::max(most_tilt, Tilt(r));
      }
    }
    // Put as it came the ball tilted the wheel-body robot 26-32° at precise and 1.5-4.9° at fast
    // (the soak's onto its side); put free, 0.4-1.2°, the robot's own strike on the wall.
    EXPECT_LT(most_tilt, kRestingTilt) << speed << " m/s: most tilt, rad";
  }
}

TEST(PlacedBall, TouchingARobotItStaysExactlyWherePut) {
  TwoRobots w("fast", "ssl-omni-2026.yaml", 0.0, 2.0);  // blue at the origin facing +x
  const Vec3 behind(-(0.09 + 0.0215), 0.0, 0.0215);     // against the round back
  EXPECT_EQ(PutBall(w, behind), behind);
  const Vec3 open(1.0, -1.0, 0.0215);
  EXPECT_EQ(PutBall(w, open), open);
}

TEST(PlacedBall, InsideARobotsShellItGoesToTheShellsSurface) {
  TwoRobots w("fast", "ssl-omni-2026.yaml", 0.0, 2.0);
  for (double a : {M_PI, 0.5 * M_PI, -0.75 * M_PI}) {  // the round side and back
    const Vec3 out(std::cos(a), std::sin(a), 0.0);
    const Vec3 put = out * (0.09 + 0.0215 - 0.012) + Vec3(0, 0, 0.0215);  // 12 mm in
    const Vec3 landed = PutBall(w, put);
    const double from_centre = landed.head<2>().norm();
    // Out along the way it went in, to within the search's ring spacing (2 mm), and free.
    EXPECT_GT(from_centre, 0.09 + 0.0215 - 0.001) << a;
    EXPECT_LT(from_centre, 0.09 + 0.0215 + 0.003) << a;
    EXPECT_GT(landed.head<2>().normalized().dot(out.head<2>()), 0.99) << a;
    EXPECT_EQ(landed.z(), put.z()) << a;
  }
}

TEST(PlacedBall, OnARobotsCentreItGoesOutThroughTheNearestFace) {
  TwoRobots w("fast", "ssl-omni-2026.yaml", 0.0, 2.0);  // blue at the origin facing +x
  const Vec3 landed = PutBall(w, Vec3(0.0, 0.0, 0.0215));
  // The flat front is the nearest way out: its face 0.07 m ahead of the centre (a little more
  // than its distance to the circle's side, 0.09 m).
  EXPECT_GT(landed.x(), 0.07 + 0.0215 - 0.001);
  EXPECT_LT(landed.head<2>().norm(), 0.07 + 0.0215 + 0.004);
  EXPECT_EQ(BallInside(*w.world), "");
}

TEST(PlacedBall, InsideAWallItGoesToTheWallsFace) {
  TwoRobots w("fast", "ssl-omni-2026.yaml", 0.0, 2.0);
  // Div B's touch-line wall has its inner face at y = 3.3: the ball put 15 mm into it.
  const Vec3 landed = PutBall(w, Vec3(1.0, 3.3 - 0.0215 + 0.015, 0.0215));
  EXPECT_NEAR(landed.x(), 1.0, 1e-9);
  EXPECT_LT(landed.y(), 3.3 - 0.0215 + 0.001);
  EXPECT_GT(landed.y(), 3.3 - 0.0215 - 0.003);
}

INSTANTIATE_TEST_SUITE_P(BothProfilesBothDrives, RobotCrash,
                         ProfilesAndDrives(), ProfileAndDriveName);

}  // namespace
}  // namespace ubersim::kernel
