// SPDX-License-Identifier: Apache-2.0
#include "robot.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <exception>

#include "ubersim/error.hpp"
#include "ubersim/kernel/upright_prism.hpp"
#include "ubersim/kernel/urdf.hpp"

namespace ubersim::kernel {

/// The RobotContext a component sees.
class Robot::Context final : public RobotContext {
 public:
  Context(Robot& robot, const ComponentModel& model, Log& log, const RobotServices& services)
      : robot_(robot),
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
    g->AddObserver(std::move(handler));
  }
  PrefixedLog& log() { return log_; }

 private:
  Robot& robot_;
  ParamView params_;
  PrefixedLog log_;
  const RobotServices& services_;
};

/// One plugin instance of the robot with its context; the context outlives the component.
struct Robot::Part {
  std::string plugin;
  PluginKind kind;
  std::unique_ptr<Context> context;
  std::shared_ptr<Component> component;
  bool failed = false;
};

Robot::Robot(const RobotPlacement& placement, NodeImpl& team_node, PluginRegistry& registry,
             Log& log, const RobotServices& services)
    : id_(placement.id), model_(placement.model), present_(placement.present) {
  const RobotModel& m = *model_;
  node_ = static_cast<NodeImpl*>(&team_node.AddChild(std::to_string(id_.id)));
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
    part->context = std::make_unique<Context>(*this, *cm, log, services);
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
    try {
      part->component->Configure(*part->context);
    } catch (const std::exception& e) {
      throw PluginError(node_->Path() + " (" + m.file + "): " + ToString(kind) + " plugin '" +
                        cm->plugin + "' failed to configure: " + e.what());
    }
    parts_.push_back(std::move(part));
  };
  add(m.drive, PluginKind::kDrive);
  add(m.dribbler, PluginKind::kDribbler);
  add(m.kicker, PluginKind::kKicker);
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
  static_cast<GeomImpl&>(node_->AddGeom(shell, chassis_)).set_prism(prism);
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
      owner.AddGeom(g, body);
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

void Robot::RunPhase(bool pre, const StepInfo& step) {
  if (!present_) return;
  for (auto& p : parts_) {
    if (p->failed) continue;
    try {
      if (pre) {
        p->component->PreStep(step);
      } else {
        p->component->PostStep(step);
      }
    } catch (const std::exception& e) {
      p->failed = true;
      p->context->log().Error(std::string(pre ? "PreStep" : "PostStep") + " threw: " + e.what() +
                              "; this " + ToString(p->kind) + " is switched off");
    }
  }
}

void Robot::PreStep(const StepInfo& step) { RunPhase(true, step); }
void Robot::PostStep(const StepInfo& step) { RunPhase(false, step); }

bool Robot::Command(const CommandEvent& e, std::string& why) {
  bool ok = true;
  auto guarded = [&](Component* c, const char* what, auto&& f) {
    if (!c) {
      why += std::string(why.empty() ? "" : "; ") + "robot has no " + what;
      ok = false;
      return;
    }
    try {
      f();
    } catch (const std::exception& ex) {
      why += std::string(why.empty() ? "" : "; ") + what + " refused the command: " + ex.what();
      ok = false;
    }
  };
  if (e.move) guarded(drive_, "drive", [&] { drive_->SetCommand(*e.move); });
  if (e.dribbler_speed) guarded(dribbler_, "dribbler", [&] { dribbler_->SetSpeed(*e.dribbler_speed); });
  if (e.kick) guarded(kicker_, "kicker", [&] { kicker_->Kick(*e.kick); });
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

RobotState Robot::State() const {
  RobotState s;
  s.id = id_;
  s.present = present_;
  s.pose = chassis_->GetPose();
  s.twist = chassis_->GetTwist();
  s.radius = model_->body.radius;
  s.height = model_->body.height;
  // A robot off the field touches nothing and kicks nothing, whatever its parts last saw.
  if (dribbler_ && present_) s.dribbler_ball_contact = dribbler_->TouchesBall();
  if (kicker_ && present_) s.kicker_ready = kicker_->Ready();
  return s;
}

}  // namespace ubersim::kernel
