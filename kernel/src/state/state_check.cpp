// SPDX-License-Identifier: Apache-2.0
#include "ubersim/kernel/state_check.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <tuple>

#include "physics/field_builder.hpp"
#include "collision/penetration.hpp"
#include "ubersim/kernel/world.hpp"
#include "state/check_world.hpp"
#include "world/world_attorney.hpp"

namespace ubersim::kernel {
namespace {

std::string Format(const char* format, double a, double b = 0, double c = 0) {
  char text[160];
  std::snprintf(text, sizeof text, format, a, b, c);
  return text;
}

std::string FormatVec(const Vec3& v) { return Format("(%.4g, %.4g, %.4g)", v.x(), v.y(), v.z()); }

std::string FormatQuat(const Quat& q) {
  char text[160];
  std::snprintf(text, sizeof text, "(%.4g, %.4g, %.4g, %.4g)", q.w(), q.x(), q.y(), q.z());
  return text;
}

bool Finite(const Pose& p, const Twist& t) {
  return p.position.allFinite() && p.orientation.coeffs().allFinite() && t.linear.allFinite() &&
         t.angular.allFinite();
}

// A body or geometry of an object with its name relative to the object's node.
struct BodyRef {
  const BodyImpl* body;
  std::string part;
};
struct GeomRef {
  const GeomImpl* geom;
  std::string part;
  bool own;  // the object's own node's, not a part's (a wheel's, a dribbler's)
};

// One object of the world with everything it owns.
struct CheckedObject {
  StateObject who;
  bool present = true;
  bool broken = false;  // has a non-finite value: no other check makes sense
  std::vector<BodyRef> bodies;
  std::vector<GeomRef> geoms;  // attached to a body and colliding
};

void Collect(const NodeImpl& node, const std::string& prefix, CheckedObject& o) {
  for (const auto& b : node.bodies()) o.bodies.push_back({b.get(), prefix + b->Name()});
  for (const auto& g : node.geoms()) {
    if (g->body() && g->collides() && !g->is_plane()) o.geoms.push_back({g.get(), prefix + g->Name(), prefix.empty()});
  }
  for (const auto& c : node.children()) Collect(*c, prefix + c->Name() + "/", o);
}

// Every object of the world, named as the scene graph's layout has them: "ball", "blue/<id>" and
// "yellow/<id>" for robots; "field" is static and checked through the walls and goals.
std::vector<CheckedObject> Objects(const WorldImpl& world) {
  std::map<std::pair<int, int>, bool> present;
  for (const RobotState& r : world.GroundTruth().robots) present[{static_cast<int>(r.id.team), r.id.id}] = r.present;
  std::vector<CheckedObject> out;
  for (const auto& child : world.scene().Root().children()) {
    const std::string& name = child->Name();
    if (name == "field") continue;
    const bool team = name == "blue" || name == "yellow";
    const auto add = [&](const NodeImpl& node, StateObject who) {
      CheckedObject o;
      o.who = std::move(who);
      Collect(node, "", o);
      return o;
    };
    if (!team) {
      StateObject who;
      who.kind = name == "ball" ? StateObject::Kind::kBall : StateObject::Kind::kOther;
      who.name = name;
      out.push_back(add(*child, who));
      continue;
    }
    for (const auto& robot : child->children()) {
      StateObject who;
      who.kind = StateObject::Kind::kRobot;
      who.robot.team = name == "blue" ? Team::kBlue : Team::kYellow;
      who.robot.id = std::atoi(robot->Name().c_str());
      who.name = "robot " + name + " " + robot->Name();
      CheckedObject o = add(*robot, who);
      const auto it = present.find({static_cast<int>(who.robot.team), who.robot.id});
      o.present = it == present.end() || it->second;
      out.push_back(std::move(o));
    }
  }
  return out;
}

// Keeps the worst finding per object, issue and other object.
class Findings {
 public:
  void Add(StateViolation v) {
    const auto key = std::make_tuple(v.object.name, static_cast<int>(v.issue), v.other ? v.other->name : v.unit);
    const auto it = index_.find(key);
    if (it == index_.end()) {
      index_[key] = list_.size();
      list_.push_back(std::move(v));
    } else if (v.value > list_[it->second].value) {
      list_[it->second] = std::move(v);
    }
  }
  std::vector<StateViolation> Take() { return std::move(list_); }

 private:
  std::map<std::tuple<std::string, int, std::string>, std::size_t> index_;
  std::vector<StateViolation> list_;
};

void CheckBodies(CheckedObject& o, const StateCheckOptions& options, const FieldModel& field, Findings& out) {
  const StateCheckLimits& lim = options.limits;
  const auto values = [](const Pose& pose, const Twist& twist) {
    return "position " + FormatVec(pose.position) + " m, velocity " + FormatVec(twist.linear) +
           " m/s, angular velocity " + FormatVec(twist.angular) + " rad/s";
  };
  for (const BodyRef& b : o.bodies) {
    const Pose pose = b.body->GetPose();
    const Twist twist = b.body->GetTwist();
    if (Finite(pose, twist)) continue;
    o.broken = true;
    if (options.finite) {
      out.Add({StateIssue::kNonFinite, o.who, b.part, std::nullopt, "", std::nan(""), 0, "",
               values(pose, twist) + ", orientation (w, x, y, z) " + FormatQuat(pose.orientation)});
    }
    return;  // the rest of this object is not worth judging
  }
  if (!o.present) return;
  for (const BodyRef& b : o.bodies) {
    const Pose pose = b.body->GetPose();
    const Twist twist = b.body->GetTwist();
    if (options.speed) {
      const double v = twist.linear.norm(), w = twist.angular.norm();
      if (v > lim.linear_speed) {
        out.Add({StateIssue::kTooFast, o.who, b.part, std::nullopt, "", v, lim.linear_speed, "m/s", values(pose, twist)});
      }
      if (w > lim.angular_speed) {
        out.Add({StateIssue::kTooFast, o.who, b.part, std::nullopt, "", w, lim.angular_speed, "rad/s",
                 values(pose, twist)});
      }
    }
    if (options.walls) {
      const double margin = field.wall.thickness + lim.wall_margin;
      if (!InsideWalls(field, pose.position, margin)) {
        const Vec3 half = WalledHalfExtents(field);
        const double beyond = std::max(std::abs(pose.position.x()) - half.x(), std::abs(pose.position.y()) - half.y()) -
                              field.wall.thickness;
        out.Add({StateIssue::kOutsideWalls, o.who, b.part, std::nullopt, "", std::max(0.0, beyond), lim.wall_margin,
                 "m", values(pose, twist)});
      }
    }
  }
}

// A robot's own bodies (its chassis, not its wheels) against upright.
void CheckTilt(const CheckedObject& o, const StateCheckLimits& lim, Findings& out) {
  if (o.who.kind != StateObject::Kind::kRobot) return;
  for (const BodyRef& b : o.bodies) {
    if (b.part.find('/') != std::string::npos) continue;  // a part's body: a wheel turns about any axis
    const Pose pose = b.body->GetPose();
    const Vec3 up = pose.orientation * Vec3::UnitZ();
    const double lean = std::acos(std::clamp(up.z(), -1.0, 1.0));
    if (lean > lim.tilt) {
      out.Add({StateIssue::kTipped, o.who, b.part, std::nullopt, "", lean, lim.tilt, "rad",
               "chassis up axis " + FormatVec(up) + ", position " + FormatVec(pose.position) + " m"});
    }
  }
}

void CheckCarpet(const CheckedObject& o, const StateCheckLimits& lim, Findings& out) {
  for (const GeomRef& g : o.geoms) {
    if (g.geom->scope() == ContactScope::kNoPlanes) continue;  // it never touches the carpet
    const Pose pose = g.geom->GetPose();
    const double lowest = PlacedShape(g.geom->GetShape(), pose).Lowest();  // the carpet is the plane z = 0
    if (-lowest > lim.carpet_penetration) {
      out.Add({StateIssue::kUnderCarpet, o.who, g.part, std::nullopt, "", -lowest, lim.carpet_penetration, "m",
               "lowest point at z = " + Format("%.4g m, geometry at ", lowest) + FormatVec(pose.position) + " m"});
    }
  }
}

// A piece of an object's hull: its geometries that other objects and walls collide with.
struct Piece {
  const CheckedObject* owner;
  StateObject who;
  std::string part;
  PlacedShape shape;
};

std::vector<Piece> HullPieces(const CheckedObject& o) {
  std::vector<Piece> out;
  if (o.broken || !o.present) return out;
  for (const GeomRef& g : o.geoms) {
    // The robot's or ball's own geometries (a robot's shell), less supports that touch only the
    // carpet. Parts that plugins add in nodes of their own (wheels, a dribbler bar) are left
    // out: a dribbler's soft bar presses into the ball by design.
    if (!g.own || g.geom->scope() == ContactScope::kPlanesOnly) continue;
    out.push_back({&o, o.who, g.part, PlacedShape(g.geom->GetShape(), g.geom->GetPose())});
  }
  return out;
}

std::vector<Piece> FieldPieces(const WorldImpl& world) {
  std::vector<Piece> out;
  const NodeImpl* field = world.scene().Root().FindChildNode("field");
  if (!field) return out;
  for (const auto& g : field->geoms()) {
    if (g->body() || !g->collides() || g->is_plane()) continue;
    StateObject who;
    who.kind = StateObject::Kind::kField;
    who.name = g->Name();
    out.push_back({nullptr, who, g->Name(), PlacedShape(g->GetShape(), g->GetPose())});
  }
  return out;
}

void CheckPair(const Piece& a, const Piece& b, double limit, Findings& out) {
  const double reach = a.shape.bounding_radius() + b.shape.bounding_radius();
  if ((a.shape.centre() - b.shape.centre()).norm() >= reach - limit) return;
  const double depth = PenetrationDepth(a.shape, b.shape, limit);
  if (depth <= limit) return;
  out.Add({StateIssue::kInsideOther, a.who, a.part, b.who, b.part, depth, limit, "m",
           a.who.name + " at " + FormatVec(a.shape.centre()) + " m, " + b.who.name + " at " +
               FormatVec(b.shape.centre()) + " m"});
}

void CheckOverlaps(const WorldImpl& world, const std::vector<CheckedObject>& objects, const StateCheckLimits& lim,
                   Findings& out) {
  std::vector<std::vector<Piece>> hulls;
  for (const CheckedObject& o : objects) hulls.push_back(HullPieces(o));
  const std::vector<Piece> field = FieldPieces(world);
  const auto limit_for = [&](const Piece& a, const Piece& b) {
    const bool ball = a.who.kind == StateObject::Kind::kBall || b.who.kind == StateObject::Kind::kBall;
    return ball ? lim.ball_penetration : lim.robot_penetration;
  };
  for (std::size_t i = 0; i < hulls.size(); ++i) {
    for (const Piece& a : hulls[i]) {
      for (std::size_t j = i + 1; j < hulls.size(); ++j) {
        for (const Piece& b : hulls[j]) CheckPair(a, b, limit_for(a, b), out);
      }
      for (const Piece& w : field) CheckPair(a, w, limit_for(a, w), out);
    }
  }
}

}  // namespace

const char* ToString(StateIssue issue) {
  switch (issue) {
    case StateIssue::kNonFinite: return "non-finite";
    case StateIssue::kTooFast: return "too fast";
    case StateIssue::kUnderCarpet: return "under the carpet";
    case StateIssue::kOutsideWalls: return "outside the walls";
    case StateIssue::kInsideOther: return "inside another";
    case StateIssue::kTipped: return "tipped";
  }
  return "?";
}

std::string StateViolation::Describe() const {
  std::string s = object.name + (part.empty() || part == object.name ? "" : " (" + part + ")") + ": ";
  switch (issue) {
    case StateIssue::kNonFinite: s += "non-finite state"; break;
    case StateIssue::kTooFast:
      s += Format("too fast: %.4g ", value) + unit + Format(", limit %.4g ", limit) + unit;
      break;
    case StateIssue::kUnderCarpet: s += Format("%.1f mm below the carpet, limit %.1f mm", 1e3 * value, 1e3 * limit); break;
    case StateIssue::kOutsideWalls: s += Format("outside the walls, %.1f mm beyond their outer faces", 1e3 * value); break;
    case StateIssue::kInsideOther:
      s += Format("%.1f mm inside ", 1e3 * value) + (other ? other->name : "?") +
           (other_part.empty() || (other && other_part == other->name) ? "" : " (" + other_part + ")") +
           Format(", limit %.1f mm", 1e3 * limit);
      break;
    case StateIssue::kTipped:
      s += Format("tipped: leaning %.1f° from upright, limit %.1f°", value * 180.0 / M_PI, limit * 180.0 / M_PI);
      break;
  }
  return s + "; " + detail;
}

std::vector<StateViolation> CheckState(const World& world, const StateCheckOptions& options) {
  return CheckState(WorldAttorney::Impl(world), options);
}

std::vector<StateViolation> CheckState(const WorldImpl& world, const StateCheckOptions& options) {
  std::vector<CheckedObject> objects = Objects(world);
  const FieldModel& field = *world.model().field;
  Findings out;
  for (CheckedObject& o : objects) {
    CheckBodies(o, options, field, out);
    if (options.carpet && !o.broken && o.present) CheckCarpet(o, options.limits, out);
    if (options.tilt && !o.broken && o.present) CheckTilt(o, options.limits, out);
  }
  if (options.overlap) CheckOverlaps(world, objects, options.limits, out);
  return out.Take();
}

}  // namespace ubersim::kernel
