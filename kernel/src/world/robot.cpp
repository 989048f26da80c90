// SPDX-License-Identifier: Apache-2.0
#include "world/robot.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <map>
#include <optional>

#include "ubersim/error.hpp"
#include "collision/surface_values.hpp"
#include "collision/upright_prism.hpp"
#include "model/urdf.hpp"

namespace ubersim::kernel {
namespace {

bool SurfaceFinite(const SurfaceMaterial& s) {
  // NaN and infinity survive a sum: one test for every contact; the values one by one only when
  // the sum is not finite (finite values may add up to infinity).
  const double sum = s.mu + s.mu2 + s.bounce + s.bounce_velocity + s.soft_erp + s.soft_cfm + s.rolling_friction +
                     s.slip + s.surface_velocity.x() + s.surface_velocity.y() + s.surface_velocity.z();
  if (std::isfinite(sum)) return true;
  return std::isfinite(s.mu) && std::isfinite(s.mu2) && std::isfinite(s.bounce) && std::isfinite(s.bounce_velocity) &&
         std::isfinite(s.soft_erp) && std::isfinite(s.soft_cfm) && std::isfinite(s.rolling_friction) &&
         std::isfinite(s.slip) && s.surface_velocity.allFinite();
}

void CollectJoints(const NodeImpl& node, std::vector<const JointImpl*>& out) {
  for (const auto& j : node.joints()) out.push_back(j.get());
  for (const auto& c : node.children()) CollectJoints(*c, out);
}

bool FeedbackFinite(const DriveFeedback& f) {
  for (double w : f.wheel_speeds) {
    if (!std::isfinite(w)) return false;
  }
  return f.local_velocity.linear.allFinite() && f.local_velocity.angular.allFinite();
}

constexpr const char* kNotStd = "threw an exception that is not a std::exception";

}  // namespace

/// One plugin instance of the robot with its context; the context outlives the component.
struct Robot::Part {
  std::string plugin;
  PluginKind kind;
  std::string file;     // the plugin's library
  std::string version;  // the plugin's own version
  std::unique_ptr<Context> context;
  std::shared_ptr<Component> component;
  std::vector<const JointImpl*> joints;  // the joints it built: their motors stop when it fails
  bool failed = false;
};

/// The RobotContext a component sees.
class Robot::Context final : public RobotContext {
 public:
  Context(Robot& robot, Part& part, const ComponentModel& model, Log& log, const RobotServices& services)
      : robot_(robot),
        part_(part),
        params_(model.params),
        log_(log, robot.node().Path() + " " + model.plugin),
        services_(services) {}

  RobotId Id() const override { return robot_.id_; }
  SceneNode& Node() override { return *robot_.node_; }
  Body& Chassis() override { return *robot_.chassis_; }
  const RobotBodyInfo& BodyInfo() const override { return robot_.model_->body; }
  const ParamView& Params() const override { return params_; }
  Log& Logger() override { return log_; }
  double SimTime() const override { return 1e-9 * static_cast<double>(*services_.sim_time_ns); }
  Body* Ball() override { return services_.ball; }
  double BallRadius() const override { return services_.ball_radius; }
  Vec3 Gravity() const override { return services_.gravity; }
  void ObserveContacts(Geom& own, ContactHandler handler) override {
    auto* g = dynamic_cast<GeomImpl*>(&own);
    bool mine = false;
    for (const NodeImpl* n = g ? &g->owner() : nullptr; n; n = n->parent()) {
      if (n == robot_.node_) mine = true;
    }
    if (!mine) {
      throw PluginError("ObserveContacts: geometry '" + own.Name() +
                        "' does not belong to robot " + robot_.node_->Path());
    }
    // The handler is plugin code running inside the collision manager: a throw or a non-finite
    // surface is this part's fault, and the contact goes on as if the handler had not run.
    // What it may change is saved as plain values, without the pair's name: a handler runs for
    // every contact of its geometry, and a string copy was most of the guard's cost.
    g->AddObserver([robot = &robot_, part = &part_, handler = std::move(handler)](
                       const Contact& contact, SurfaceMaterial& surface, bool& accept) {
      if (part->failed) return;
      const SurfaceValues before = SurfaceValues::Of(surface);
      const bool accepted = accept;
      const char* fault = nullptr;
      std::string thrown;
      try {
        handler(contact, surface, accept);
        if (!SurfaceFinite(surface)) fault = "set a non-finite surface value";
      } catch (const std::exception& e) {
        thrown = "threw " + ExceptionText(e);
        fault = thrown.c_str();
      } catch (...) {
        fault = kNotStd;
      }
      if (!fault) return;
      before.WriteTo(surface);
      accept = accepted;
      robot->Fail(*part, "contact handler", fault);
    });
  }
  SurfaceMaterial CarpetSurface(const SurfaceMaterial& own) const override {
    return services_.materials->Resolve(own, services_.carpet);
  }
  PrefixedLog& log() { return log_; }

 private:
  Robot& robot_;
  Part& part_;
  ParamView params_;
  PrefixedLog log_;
  const RobotServices& services_;
};

Robot::Robot(const RobotPlacement& placement, NodeImpl& team_node, PluginRegistry& registry,
             Log& log, const RobotServices& services)
    : id_(placement.id),
      services_(services),
      log_(log, "robot " + ToString(placement.id)),
      model_(placement.model),
      present_(placement.present) {
  const RobotModel& m = *model_;
  node_ = static_cast<NodeImpl*>(&team_node.AddChild(std::to_string(id_.id)));
  node_->set_robot();  // before any part: every geometry below knows its robot
  if (m.urdf_file.empty()) {
    BuildCylinderChassis(placement);
  } else {
    BuildUrdfBodies(placement);
  }

  auto add = [&](const std::optional<ComponentModel>& cm, PluginKind kind) {
    if (!cm) return;
    auto part = std::make_unique<Part>();
    part->plugin = cm->plugin;
    part->kind = kind;
    part->context = std::make_unique<Context>(*this, *part, *cm, log, services);
    switch (kind) {
      case PluginKind::kDrive: {
        auto d = registry.CreateDrive(cm->plugin);
        drive_ = d.get();
        part->component = std::move(d);
        break;
      }
      case PluginKind::kDribbler: {
        auto d = registry.CreateDribbler(cm->plugin);
        dribbler_ = d.get();
        part->component = std::move(d);
        break;
      }
      case PluginKind::kKicker: {
        auto k = registry.CreateKicker(cm->plugin);
        kicker_ = k.get();
        part->component = std::move(k);
        break;
      }
      case PluginKind::kTransport: break;
    }
    const PluginInfo& info = registry.Find(kind, cm->plugin);
    part->file = info.file.string();
    part->version = info.version;
    std::vector<const JointImpl*> before;
    CollectJoints(*node_, before);
    Part& p = *part;
    parts_.push_back(std::move(part));
    if (kind != PluginKind::kTransport) part_of_[static_cast<std::size_t>(kind) - 1] = &p;  // PartOf's
    // Any exception from Configure means the robot cannot be built as its model file says: a
    // load error naming the robot, its model file, the plugin, its library and the reason (exit 4
    // from the CLI; `ubersim validate` runs Configure too), never a fault of a running world.
    const auto refused = [&](const std::string& why) {
      return PluginError(node_->Path() + " (" + m.file + "): " + ToString(kind) + " plugin '" + cm->plugin +
                         "' (" + p.file + ") failed to configure: " + why);
    };
    try {
      p.component->Configure(*p.context);
    } catch (const PluginError& e) {
      throw refused(e.what());
    } catch (const ParamError& e) {
      throw refused(e.what());
    } catch (const std::exception& e) {
      throw refused(ExceptionText(e));
    } catch (...) {
      throw refused(kNotStd);
    }
    std::vector<const JointImpl*> after;
    CollectJoints(*node_, after);
    for (const JointImpl* j : after) {
      if (std::find(before.begin(), before.end(), j) == before.end()) p.joints.push_back(j);
    }
  };
  add(m.drive, PluginKind::kDrive);
  add(m.dribbler, PluginKind::kDribbler);
  add(m.kicker, PluginKind::kKicker);
  node_->ForEachBody([this](BodyImpl& b) { watch_.Add(b); });
  if (services_.ball) watch_.Add(*services_.ball);
  if (!present_) {
    present_ = true;
    SetPresent(false);
  }
}

void Robot::BuildCylinderChassis(const RobotPlacement& placement) {
  const RobotBodyInfo& b = model_->body;
  const double length = b.height - b.ground_clearance;
  const double shell_centre = b.ground_clearance + 0.5 * length;
  // The body origin is the centre of mass (ODE's convention); the shell sits around it.
  rest_height_ = b.center_of_mass_height >= 0 ? b.center_of_mass_height : shell_centre;
  BodySpec chassis;
  chassis.name = "chassis";
  chassis.mass = MassSpec::Solid(Shape::Cylinder(b.radius, length), b.mass);
  chassis.pose = Pose::FromYaw(Vec3(placement.x, placement.y, rest_height_), placement.yaw);
  chassis_ = static_cast<BodyImpl*>(&node_->AddBody(chassis));
  GeomSpec shell;
  shell.name = "shell";
  const FlatFrontPrism prism{b.radius, std::min(b.front_distance, b.radius), 0.5 * length};
  shell.shape = b.front_distance < b.radius ? FlatFrontPrismMesh(prism) : Shape::Cylinder(b.radius, length);
  shell.material = model_->surface;
  shell.offset.position = Vec3(0, 0, shell_centre - rest_height_);
  // Marked as the prism it is: two upright shells then meet exactly and fast (and two cylinder
  // shells meet at all: ODE has no cylinder-cylinder test).
  auto& hull = static_cast<GeomImpl&>(node_->AddGeom(shell, chassis_));
  hull.set_prism(prism);
  hull.set_hull(true);
}

void Robot::BuildUrdfBodies(const RobotPlacement& placement) {
  const UrdfRobot urdf = LoadUrdf(model_->urdf_file);
  const UrdfLink& root = urdf.links.front();
  if (std::abs(root.mass.mass - model_->body.mass) > 0.01 * model_->body.mass) {
    throw ModelError(model_->file, 0, 0, "body.mass",
                     "body.mass " + std::to_string(model_->body.mass) + " kg differs from the URDF root link '" +
                         root.name + "' mass " + std::to_string(root.mass.mass) + " kg (" + urdf.file + ")");
  }
  // The root link's frame stands on the carpet where the robot is placed.
  const Pose ground = Pose::FromYaw(Vec3(placement.x, placement.y, 0.0), placement.yaw);
  std::map<std::string, BodyImpl*> bodies;
  for (std::size_t i = 0; i < urdf.links.size(); ++i) {
    const UrdfLink& link = urdf.links[i];
    const bool is_root = i == 0;
    NodeImpl& owner = is_root ? *node_ : static_cast<NodeImpl&>(node_->AddChild(link.name));
    const Pose com_in_root = link.pose.Compose(link.inertial_origin);
    BodySpec spec;
    spec.name = is_root ? "chassis" : link.name;
    spec.mass = link.mass;
    spec.pose = ground.Compose(com_in_root);
    auto* body = static_cast<BodyImpl*>(&owner.AddBody(spec));
    bodies[link.name] = body;
    if (is_root) {
      chassis_ = body;
      rest_height_ = com_in_root.position.z();
    }
    // Geometry offsets are relative to the body origin, the COM.
    const Pose com_inverse{-(link.inertial_origin.orientation.conjugate() * link.inertial_origin.position),
                           link.inertial_origin.orientation.conjugate()};
    for (std::size_t c = 0; c < link.collisions.size(); ++c) {
      GeomSpec g;
      g.name = (is_root ? std::string("shell") : link.name) + (c ? "_" + std::to_string(c) : "");
      g.shape = link.collisions[c].shape;
      g.offset = com_inverse.Compose(link.collisions[c].origin);
      g.material = model_->surface;
      // The root link's collision shapes are the robot's hull (what another robot touches).
      static_cast<GeomImpl&>(owner.AddGeom(g, body)).set_hull(is_root);
    }
  }
  for (const UrdfJoint& j : urdf.joints) {
    const auto link_it = std::find_if(urdf.links.begin(), urdf.links.end(),
                                      [&](const UrdfLink& l) { return l.name == j.child; });
    const Pose child_frame = ground.Compose(link_it->pose);
    JointSpec spec;
    spec.name = j.name;
    spec.kind = j.kind;
    spec.parent = bodies.at(j.parent);
    spec.child = bodies.at(j.child);
    spec.anchor = child_frame.position;
    spec.axis = child_frame.orientation * (j.axis.norm() > 0 ? j.axis.normalized() : Vec3::UnitX());
    spec.lower_limit = j.lower;
    spec.upper_limit = j.upper;
    NodeImpl* owner = node_->FindChildNode(j.child);  // the child link's node holds the joint
    (owner ? owner : node_)->AddJoint(spec);
  }
}

Robot::~Robot() {
  // Observers are plugin code: drop them while the plugin libraries are still loaded.
  node_->ForEachGeom([](GeomImpl& g) { g.ClearObservers(); });
  parts_.clear();
}

void Robot::Fail(Part& p, const std::string& phase, const std::string& what) {
  if (p.failed) return;
  p.failed = true;
  for (const JointImpl* j : p.joints) StopMotor(*j);
  PluginFault f;
  f.robot = id_;
  f.kind = p.kind;
  f.plugin = p.plugin;
  f.file = p.file;
  f.phase = phase;
  f.what = what;
  if (services_.faults) {
    services_.faults->Report(std::move(f));
  } else {
    p.context->log().Error(f.Describe() + "; this " + ToString(p.kind) + " is switched off");
  }
}

template <typename F>
bool Robot::Guarded(Part& p, const char* phase, F&& call) {
  if (p.failed) return false;
  try {
    call();
  } catch (const std::exception& e) {
    Fail(p, phase, "threw " + ExceptionText(e));
  } catch (...) {
    Fail(p, phase, kNotStd);
  }
  if (!watch_.AllFinite()) ReportNonFinite(p, phase);
  return !p.failed;
}

template <typename F>
void Robot::Queried(Part& p, const char* phase, F&& call) const {
  if (p.failed) return;
  try {
    call();
  } catch (const std::exception& e) {
    const_cast<Robot&>(*this).Fail(p, phase, "threw " + ExceptionText(e));
  } catch (...) {
    const_cast<Robot&>(*this).Fail(p, phase, kNotStd);
  }
}

void Robot::ReportNonFinite(Part& p, const char* phase) {
  std::string where = FindNonFinite(*node_);
  if (where.empty() && services_.ball) where = "ball: " + NonFiniteIn(*services_.ball);
  Fail(p, phase, "left a non-finite value: " + where);
  Repair();
}

void Robot::Repair() {
  if (!services_.last_good) return;
  kernel::RepairNonFinite(*node_, *services_.last_good);
  if (services_.ball && !NonFiniteIn(*services_.ball).empty()) services_.last_good->Restore(*services_.ball);
}

void Robot::RunPhase(bool pre, const StepInfo& step) {
  if (!present_) return;
  for (auto& p : parts_) {
    if (pre) {
      Guarded(*p, "PreStep", [&] { p->component->PreStep(step); });
    } else {
      Guarded(*p, "PostStep", [&] { p->component->PostStep(step); });
    }
  }
}

void Robot::RepairNonFinite(const char* when, std::int64_t step, const std::string& what) {
  const bool again = step - repaired_at_ <= 1;
  repaired_at_ = step;
  PluginFault f;
  f.robot = id_;
  f.phase = when;
  f.what = what + " (no plugin call left a non-finite value)";
  if (services_.faults) services_.faults->Report(std::move(f));
  if (services_.last_good) kernel::RepairNonFinite(*node_, *services_.last_good);  // its own bodies only
  if (again && present_) {
    // Put back twice running: whatever drives it there will do it again; off the field it
    // harms nothing, and a position event can put it back.
    SetPresent(false);
    log_.Error("went non-finite in two steps running: taken off the field");
  }
}

void Robot::PreStep(const StepInfo& step) { RunPhase(true, step); }
void Robot::PostStep(const StepInfo& step) { RunPhase(false, step); }

bool Robot::Command(const CommandEvent& e, std::string& why) {
  bool ok = true;
  const auto refuse = [&](const std::string& reason) {
    why += (why.empty() ? "" : "; ") + reason;
    ok = false;
  };
  // PluginError is the part refusing this command (a wheel count that does not fit): the
  // command is rejected and the part carries on. Anything else is a fault of the part.
  const auto deliver = [&](PluginKind kind, const char* phase, auto&& call) {
    Part* part = PartOf(kind);
    if (!part) return refuse(std::string("robot has no ") + ToString(kind));
    if (part->failed) return refuse(std::string("its ") + ToString(kind) + " is switched off after a fault");
    const bool alive = Guarded(*part, phase, [&] {
      try {
        call();
      } catch (const PluginError& ex) {
        refuse(std::string(ToString(kind)) + " refused the command: " + ex.what());
      }
    });
    if (!alive) refuse(std::string(ToString(kind)) + " failed on the command");
  };
  if (e.move) deliver(PluginKind::kDrive, "SetCommand", [&] { drive_->SetCommand(*e.move); });
  if (e.dribbler_speed) {
    deliver(PluginKind::kDribbler, "SetSpeed", [&] { dribbler_->SetSpeed(*e.dribbler_speed); });
    dribbler_speed_ = *e.dribbler_speed;
  }
  if (e.kick) deliver(PluginKind::kKicker, "Kick", [&] { kicker_->Kick(*e.kick); });
  return ok;
}

void Robot::Teleport(double x, double y, double yaw) {
  const Pose old_chassis = chassis_->GetPose();
  const Pose new_chassis = Pose::FromYaw(Vec3(x, y, rest_height_), yaw);
  const Quat dq = (new_chassis.orientation * old_chassis.orientation.conjugate()).normalized();
  node_->ForEachBody([&](BodyImpl& body) {
    const Pose p = body.GetPose();
    const Vec3 rel = p.position - old_chassis.position;
    body.SetPose(Pose{new_chassis.position + dq * rel, (dq * p.orientation).normalized()});
    const Twist t = body.GetTwist();
    body.SetTwist(Twist{dq * t.linear, dq * t.angular});
  });
}

void Robot::SetVelocity(const Vec3& linear, const Vec3& angular) {
  const Vec3 origin = chassis_->GetPose().position;
  node_->ForEachBody([&](BodyImpl& body) {
    const Vec3 r = body.GetPose().position - origin;
    body.SetTwist(Twist{linear + angular.cross(r), angular});
  });
}

void Robot::Placed() {
  if (Part* p = PartOf(PluginKind::kDrive)) Guarded(*p, "Placed", [&] { drive_->Placed(); });
}

void Robot::SetPresent(bool present) {
  if (present == present_) return;
  present_ = present;
  node_->ForEachGeom([&](GeomImpl& g) { g.SetCollides(present); });
  node_->ForEachBody([&](BodyImpl& body) {
    if (present) {
      dBodyEnable(body.id());
    } else {
      body.SetTwist(Twist{});
      dBodyDisable(body.id());
    }
  });
}

RobotState Robot::Kinematics() const {
  RobotState s;
  WriteKinematics(s);
  return s;
}

void Robot::WriteKinematics(RobotState& s) const {
  s.id = id_;
  s.present = present_;
  s.pose = chassis_->GetPose();
  s.twist = chassis_->GetTwist();
  s.radius = model_->body.radius;
  s.height = model_->body.height;
}

bool Robot::TouchesBall() const {
  bool touches = false;
  Part* p = PartOf(PluginKind::kDribbler);
  if (p && !p->failed) Queried(*p, "TouchesBall", [&] { touches = dribbler_->TouchesBall(); });
  return touches;
}

RobotState Robot::State() const {
  RobotState s = Kinematics();
  // A robot off the field touches nothing and kicks nothing, whatever its parts last saw; a
  // part switched off reports nothing.
  if (!present_) return s;
  for (const auto& p : parts_) {
    if (p->kind == PluginKind::kDribbler) {
      Queried(*p, "TouchesBall", [&] { s.dribbler_ball_contact = dribbler_->TouchesBall(); });
    } else if (p->kind == PluginKind::kKicker) {
      Queried(*p, "Ready", [&] { s.kicker_ready = kicker_->Ready(); });
    } else if (p->kind == PluginKind::kDrive) {
      std::optional<DriveFeedback> f;
      Queried(*p, "Feedback", [&] { f = drive_->Feedback(); });
      // What a drive reports goes out on the wire and into learners' arrays: a non-finite value
      // is the drive's defect, switched off like one it left in the physics.
      if (f && !FeedbackFinite(*f)) {
        const_cast<Robot&>(*this).Fail(*p, "Feedback", "reported a non-finite wheel speed or velocity");
      } else {
        s.drive = std::move(f);
      }
    }
  }
  return s;
}

std::vector<PartState> Robot::SaveParts() const {
  std::vector<PartState> out;
  for (const auto& p : parts_) {
    PartState ps;
    ps.kind = p->kind;
    ps.plugin = p->plugin;
    ps.version = p->version;
    ps.failed = p->failed;
    if (p->failed) {  // switched off for good: whatever it holds is not asked for
      out.push_back(std::move(ps));
      continue;
    }
    try {
      ps.state = p->component->SaveState();
    } catch (const std::exception& e) {
      throw PluginError(node_->Path() + " " + ToString(p->kind) + " '" + p->plugin + "' (" + p->file +
                        "): SaveState threw " + ExceptionText(e));
    } catch (...) {
      throw PluginError(node_->Path() + " " + ToString(p->kind) + " '" + p->plugin + "' (" + p->file + "): SaveState " +
                        kNotStd);
    }
    out.push_back(std::move(ps));
  }
  return out;
}

void Robot::RestoreParts(const std::vector<PartState>& parts) {
  if (parts.size() != parts_.size()) {
    throw PluginError("robot " + node_->Path() + " has " + std::to_string(parts_.size()) + " parts, the snapshot " +
                      std::to_string(parts.size()));
  }
  for (std::size_t i = 0; i < parts.size(); ++i) {
    Part& p = *parts_[i];
    const PartState& saved = parts[i];
    const std::string who = node_->Path() + " " + ToString(p.kind) + " '" + p.plugin + "'";
    if (saved.kind != p.kind || saved.plugin != p.plugin) {
      throw PluginError(who + ": the snapshot has " + ToString(saved.kind) + " '" + saved.plugin + "' here");
    }
    if (saved.failed) {  // stays off, as in the snapshot (its fault is in the snapshot's list)
      if (!p.failed) {
        p.failed = true;
        for (const JointImpl* j : p.joints) StopMotor(*j);
      }
      continue;
    }
    if (p.failed) throw PluginError(who + " failed while this world was built; in the snapshot it runs");
    if (saved.version != p.version) {
      p.context->log().Warning("restoring state saved by version " + saved.version + " into version " + p.version);
    }
    try {
      p.component->RestoreState(saved.state);
    } catch (const std::exception& e) {
      throw PluginError(who + " (" + p.file + ") refused its saved state: " + e.what());
    } catch (...) {
      throw PluginError(who + " (" + p.file + ") refused its saved state: " + kNotStd);
    }
  }
}

}  // namespace ubersim::kernel
