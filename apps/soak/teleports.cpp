// SPDX-License-Identifier: Apache-2.0
#include "teleports.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "ubersim/kernel/field.hpp"

namespace ubersim::kernel::soak {
namespace {

constexpr double kRobotSpeed = 3.0;     // m/s: the modern robots' top speed (their drive limits)
constexpr double kRobotSpin = 10.0;     // rad/s: their top turning rate
constexpr double kBallSpeed = 6.5;      // m/s: the rules' ball speed limit
constexpr double kLowestWall = 0.05;    // m: boxes lower than this are goal roofs, not walls
constexpr std::int64_t kNever = std::numeric_limits<std::int64_t>::min() / 2;

std::pair<bool, std::pair<int, int>> Key(const Target& t) {
  if (t.is_ball) return {true, {0, 0}};
  return {false, {static_cast<int>(t.robot.team), t.robot.id}};
}

}  // namespace

const char* ToString(TeleportKind kind) {
  switch (kind) {
    case TeleportKind::kRobotOntoRobot: return "robot onto robot";
    case TeleportKind::kRobotIntoWall: return "robot into wall";
    case TeleportKind::kRobotAnywhere: return "robot anywhere";
    case TeleportKind::kBallOntoRobot: return "ball onto robot";
    case TeleportKind::kBallIntoWall: return "ball into wall";
    case TeleportKind::kBallShot: return "ball shot at robot";
  }
  return "?";
}

RandomTeleports::RandomTeleports(World& world, std::uint64_t seed, double mean_interval, double wall_overlap)
    : world_(world), rng_(seed), mean_interval_(mean_interval), wall_overlap_(wall_overlap) {
  for (const RobotState& r : world.Kinematics().robots) {
    robots_.push_back(r.id);
    robot_radius_ = r.radius;
  }
  for (const RobotPlacement& p : world.model().robots) {
    hulls_.push_back({p.id, p.model->body.radius, std::min(p.model->body.front_distance, p.model->body.radius)});
  }
  ball_radius_ = world.model().ball->radius;
  FindFaces();
  std::exponential_distribution<double> gap(1.0 / mean_interval_);
  next_ns_ = world.clock().time_ns() + static_cast<std::int64_t>(gap(rng_) * 1e9);
}

void RandomTeleports::FindFaces() {
  for (const FieldWall& w : FieldWalls(world_)) {
    if (w.size.z() < kLowestWall) continue;
    boxes_.push_back({w.pose, 0.5 * w.size});
  }
  for (const Box& b : boxes_) {
    // Field boxes only turn about z: their local x and y faces are the vertical ones.
    for (int axis = 0; axis < 2; ++axis) {
      for (double sign : {-1.0, 1.0}) {
        Face f;
        f.normal = b.pose.orientation * (sign * Vec3::Unit(axis));
        f.along = b.pose.orientation * Vec3::Unit(1 - axis);
        f.centre = b.pose.position + f.normal * b.half[axis];
        f.centre.z() = 0.0;
        f.half_length = b.half[1 - axis];
        f.thickness = 2.0 * b.half[axis];
        // Only faces something can stand in front of: the robot's width out from its middle is free.
        if (Free(f.centre + f.normal * 2.0 * robot_radius_, 0.0)) faces_.push_back(f);
      }
    }
  }
}

bool RandomTeleports::Resolvable(const Vec3& p, double radius) const {
  int thin = 0;  // thin walls (a goal's) it overlaps
  for (const Box& b : boxes_) {
    const Vec3 local = b.pose.orientation.conjugate() * (p - b.pose.position);
    const double dx = std::max(0.0, std::abs(local.x()) - b.half.x());
    const double dy = std::max(0.0, std::abs(local.y()) - b.half.y());
    const double overlap = radius - std::hypot(dx, dy);
    const double thickness = 2.0 * std::min(b.half.x(), b.half.y());
    if (overlap <= 0.0) continue;
    if (overlap > wall_overlap_ * thickness) return false;
    if (thickness < radius) ++thin;
  }
  return thin < 2;  // two thin walls meeting (a goal's corner) would poke right into it
}

bool RandomTeleports::Free(const Vec3& p, double radius) const {
  if (!InsideWalls(*world_.model().field, p, -radius)) return false;
  for (const Box& b : boxes_) {
    const Vec3 local = b.pose.orientation.conjugate() * (p - b.pose.position);
    if (std::abs(local.x()) < b.half.x() + radius && std::abs(local.y()) < b.half.y() + radius) return false;
  }
  return true;
}

Vec3 RandomTeleports::RandomFreePoint(double radius) {
  const Vec3 half = WalledHalfExtents(*world_.model().field);
  std::uniform_real_distribution<double> x(-half.x(), half.x()), y(-half.y(), half.y());
  const WorldSnapshot s = world_.Kinematics();
  Vec3 p = Vec3::Zero();
  for (int attempt = 0; attempt < 100; ++attempt) {
    // One draw a statement: the order of a call's arguments is the compiler's, and a seed must
    // give one run whatever built it. y first, as gcc evaluated the old one-call form.
    const double py = y(rng_);
    const double px = x(rng_);
    p = Vec3(px, py, 0.0);
    bool clear = Free(p, radius + 0.02);
    for (const RobotState& r : s.robots) {
      if (clear && (r.pose.position - p).head<2>().norm() < r.radius + radius + 0.05) clear = false;
    }
    if (clear) return p;
  }
  return p;  // a crowded field: the last try (the physics parts whatever overlaps)
}

Vec3 RandomTeleports::RandomVelocity(double max_speed, const std::optional<Vec3>& towards) {
  std::uniform_real_distribution<double> unit(0.0, 1.0), angle(-M_PI, M_PI);
  // Half the time at full speed, half slower; half the time straight at the target.
  const double speed = unit(rng_) < 0.5 ? max_speed : max_speed * unit(rng_);
  Vec3 direction(0, 0, 0);
  if (towards && towards->head<2>().norm() > 1e-9 && unit(rng_) < 0.5) {
    direction = Vec3(towards->x(), towards->y(), 0.0).normalized();
  } else {
    const double a = angle(rng_);
    direction = Vec3(std::cos(a), std::sin(a), 0.0);
  }
  return speed * direction;
}

RobotId RandomTeleports::RandomRobot() {
  std::uniform_int_distribution<std::size_t> pick(0, robots_.size() - 1);
  return robots_[pick(rng_)];
}

void RandomTeleports::PostRobot(const RobotId& id, const Vec3& position, double yaw, const Vec3& velocity,
                                double spin) {
  PositionEvent e;
  e.target = Target::Robot(id);
  e.position = position;
  e.yaw = yaw;
  e.velocity = velocity;
  e.angular_velocity = Vec3(0, 0, spin);
  if (observer_) observer_(doing_, e);
  world_.events().Post(e);
  MarkMoved(e.target);
}

void RandomTeleports::PostBall(const Vec3& position, const Vec3& velocity) {
  PositionEvent e;
  e.target = Target::Ball();
  e.position = Vec3(position.x(), position.y(), 0.0);  // z 0: resting on the carpet
  e.velocity = velocity;
  e.angular_velocity = Vec3::Zero();
  if (observer_) observer_(doing_, e);
  world_.events().Post(e);
  MarkMoved(e.target);
}

std::optional<TeleportKind> RandomTeleports::BeforeStep() {
  const std::int64_t now = world_.clock().time_ns();
  if (now < next_ns_) return std::nullopt;
  std::exponential_distribution<double> gap(1.0 / mean_interval_);
  next_ns_ = now + std::max<std::int64_t>(1, static_cast<std::int64_t>(gap(rng_) * 1e9));
  std::uniform_int_distribution<int> kind(0, kTeleportKinds - 1);
  const auto k = static_cast<TeleportKind>(kind(rng_));
  Teleport(k);
  return k;
}

void RandomTeleports::Teleport(TeleportKind kind) {
  if (robots_.empty()) kind = TeleportKind::kBallIntoWall;  // the only kind without a robot
  ++counts_[static_cast<int>(kind)];
  doing_ = ToString(kind);
  std::uniform_real_distribution<double> unit(0.0, 1.0), angle(-M_PI, M_PI);
  const WorldSnapshot s = world_.Kinematics();
  const auto state_of = [&](const RobotId& id) -> const RobotState& {
    for (const RobotState& r : s.robots) {
      if (r.id == id) return r;
    }
    return s.robots.front();
  };
  const Vec3 ball = s.ball.pose.position;
  // A robot put down moving: its turn rate drawn before its velocity (one draw a statement, as
  // gcc evaluated the old PostRobot(…, RandomVelocity(…), spin()) call).
  const auto post_moving = [&](const RobotId& a, const Vec3& p, double yaw, const std::optional<Vec3>& towards) {
    const double spin = kRobotSpin * (2.0 * unit(rng_) - 1.0);
    const Vec3 velocity = RandomVelocity(kRobotSpeed, towards);
    PostRobot(a, p, yaw, velocity, spin);
  };
  // A point overlapping a wall face by up to `share` of the wall's thickness (at most `reach`,
  // the object's extent towards the wall), its centre in front of the face.
  const auto against_wall = [&](const std::function<double(const Vec3&)>& reach, double share,
                                Vec3& normal) -> std::optional<Vec3> {
    if (faces_.empty()) return std::nullopt;
    std::uniform_int_distribution<std::size_t> pick(0, faces_.size() - 1);
    const Face& f = faces_[pick(rng_)];
    const double along = (2.0 * unit(rng_) - 1.0) * f.half_length;
    const double extent = reach(-f.normal);
    // At least a fifth of the most: a shell is a polygon a little inside its circle.
    const double overlap = (0.2 + 0.8 * unit(rng_)) * std::min(extent, share * f.thickness);
    const Vec3 p = f.centre + f.along * along + f.normal * (extent - overlap);
    if (!Free(p, 0.0)) return std::nullopt;
    normal = f.normal;
    return p;
  };
  // Tries a few random placements; a teleport that finds none is left out.
  for (int attempt = 0; attempt < 20; ++attempt) {
    switch (kind) {
      case TeleportKind::kRobotOntoRobot: {
        const RobotId a = RandomRobot();
        RobotId b = RandomRobot();
        for (int i = 0; i < 10 && b == a && robots_.size() > 1; ++i) b = RandomRobot();
        const Vec3 on = state_of(b).pose.position;
        const Vec3 p = on + Around(2.0 * robot_radius_ * unit(rng_));
        const double yaw = angle(rng_);
        if (TrapsBall(a, p, yaw, ball) || !Free(p, 0.0) || !Resolvable(p, robot_radius_)) continue;
        post_moving(a, p, yaw, on - p);
        MarkMoved(Target::Robot(b));
        return;
      }
      case TeleportKind::kRobotIntoWall: {
        const RobotId a = RandomRobot();
        const double yaw = angle(rng_);
        const auto hull = [&](const Vec3& towards) { return HullReach(a, yaw, std::atan2(towards.y(), towards.x())); };
        Vec3 normal = Vec3::Zero();  // set by against_wall when it finds a spot
        const std::optional<Vec3> p = against_wall(hull, wall_overlap_, normal);
        if (!p || TrapsBall(a, *p, yaw, ball) || !Resolvable(*p, robot_radius_)) continue;
        post_moving(a, *p, yaw, -normal);
        return;
      }
      case TeleportKind::kRobotAnywhere: {
        const RobotId a = RandomRobot();
        const Vec3 p = RandomFreePoint(robot_radius_);
        const double yaw = angle(rng_);
        if (TrapsBall(a, p, yaw, ball)) continue;
        post_moving(a, p, yaw, std::nullopt);
        return;
      }
      case TeleportKind::kBallOntoRobot: {
        // Overlapping the robot's hull by up to the ball's radius, its centre outside the hull.
        const RobotState& r = state_of(RandomRobot());
        const double a = angle(rng_);
        const Vec3 direction(std::cos(a), std::sin(a), 0.0);
        const Vec3 p = r.pose.position + direction * (HullReach(r.id, r.pose.Yaw(), a) + ball_radius_ * unit(rng_));
        if (InsideARobot(p, s) || !Free(p, 0.0)) continue;
        PostBall(p, RandomVelocity(kBallSpeed, r.pose.position - p));
        MarkMoved(Target::Robot(r.id));
        return;
      }
      case TeleportKind::kBallIntoWall: {
        Vec3 normal = Vec3::Zero();  // set by against_wall when it finds a spot
        // The ball is a solid sphere to the collision code: up to its radius, its centre in front.
        const std::optional<Vec3> p = against_wall([&](const Vec3&) { return ball_radius_; }, 1.0, normal);
        if (!p || InsideARobot(*p, s)) continue;
        PostBall(*p, RandomVelocity(kBallSpeed, -normal));
        return;
      }
      case TeleportKind::kBallShot: {
        const Vec3 p = RandomFreePoint(ball_radius_);
        if (InsideARobot(p, s)) continue;
        const Vec3 to = state_of(RandomRobot()).pose.position - p;
        PostBall(p, to.head<2>().norm() > 1e-9 ? Vec3(to.x(), to.y(), 0).normalized() * kBallSpeed : Vec3(kBallSpeed, 0, 0));
        return;
      }
    }
  }
  --counts_[static_cast<int>(kind)];  // nowhere to put it this time
}

Vec3 RandomTeleports::Around(double distance) {
  std::uniform_real_distribution<double> angle(-M_PI, M_PI);
  const double a = angle(rng_);
  return Vec3(distance * std::cos(a), distance * std::sin(a), 0.0);
}

double RandomTeleports::HullReach(const RobotId& id, double yaw, double direction) const {
  double radius = robot_radius_, front = robot_radius_;
  for (const Hull& h : hulls_) {
    if (h.id == id) {
      radius = h.radius;
      front = h.front_distance;
    }
  }
  // A circle cut flat at `front` ahead: the flat face spans ±acos(front / radius) about the heading.
  const double off = std::remainder(direction - yaw, 2.0 * M_PI);
  const double cut = std::acos(std::clamp(front / radius, -1.0, 1.0));
  return std::abs(off) < cut ? front / std::cos(off) : radius;
}

bool RandomTeleports::TrapsBall(const RobotId& id, const Vec3& at, double yaw, const Vec3& ball) const {
  const Vec3 d = ball - at;
  return d.head<2>().norm() < HullReach(id, yaw, std::atan2(d.y(), d.x()));
}

bool RandomTeleports::InsideARobot(const Vec3& p, const WorldSnapshot& s) const {
  for (const RobotState& r : s.robots) {
    if (r.present && TrapsBall(r.id, r.pose.position, r.pose.Yaw(), p)) return true;
  }
  return false;
}

void RandomTeleports::Replace(const Target& target) {
  doing_ = "put back";
  if (target.is_ball) {
    PostBall(RandomFreePoint(ball_radius_), Vec3::Zero());
  } else {
    std::uniform_real_distribution<double> angle(-M_PI, M_PI);
    const Vec3 ball = world_.Kinematics().ball.pose.position;
    Vec3 p = RandomFreePoint(robot_radius_);
    double yaw = angle(rng_);
    for (int attempt = 0; attempt < 20 && TrapsBall(target.robot, p, yaw, ball); ++attempt) {
      p = RandomFreePoint(robot_radius_);
      yaw = angle(rng_);
    }
    PostRobot(target.robot, p, yaw, Vec3::Zero(), 0.0);
  }
}

void RandomTeleports::MarkMoved(const Target& target) { last_moved_[Key(target)] = world_.clock().time_ns(); }

std::int64_t RandomTeleports::LastMoved(const Target& target) const {
  const auto it = last_moved_.find(Key(target));
  return it == last_moved_.end() ? kNever : it->second;
}

}  // namespace ubersim::kernel::soak
