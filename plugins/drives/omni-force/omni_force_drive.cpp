// SPDX-License-Identifier: Apache-2.0
// omni_force: the omni drive as one rigid body per robot, for speed.
//
// The omni drive makes a body per wheel on a motorised hinge and lets ODE's contact friction move
// the robot. This drive makes no wheel bodies. The chassis stands on one frictionless sphere per
// wheel (the wheel's radius, at the wheel's centre: the same height as on wheels), and every step
// each wheel's force on the carpet is computed and applied to the chassis at the wheel's contact
// point, as the ER-Force simulator drives its robots:
//
//   - along the rolling direction the wheel's motor is a velocity servo against the carpet: it
//     pushes the contact point toward the wheel's surface speed ω·r with the force that would get
//     there in one step if it moved its share of the robot (mass / wheel count), at most the
//     motor's max_torque / r and at most mu_roll times its share of the weight;
//   - along the axle the free rollers resist sliding with at most mu_axle times that share.
//
// Simplifications: each wheel carries a fixed share of the weight (m·g / n) whatever the robot
// does — no load transfer while braking or turning, as in ER-Force's simulator — and a wheel has
// no inertia of its own (the motor's torque goes straight to the carpet). The servo loop, the
// wheel geometry and the command handling are the omni drive's, so both drives follow the same
// setpoints and report the same feedback.
#include <algorithm>
#include <cmath>
#include <string>
#include <variant>
#include <vector>

#include <Eigen/Dense>
#include <ubersim/ubersim.hpp>

#include "ubersim_plugin_schema.hpp"

namespace {

using ubersim::Vec3;

struct Wheel {
  Vec3 centre;        // wheel centre in the chassis frame (origin at the centre of mass), m
  Vec3 tangent;       // rolling direction in the robot frame (counter-clockwise)
  double mu_roll = 0.8;   // carpet friction along the rolling direction, as last resolved
  double mu_axle = 0.05;  // along the axle (the rollers), as last resolved
};

// A wheel grips while its lowest point is at most this far above the carpet, m. Geometric, not
// "its support made a contact this step": a sphere resting on the carpet touches it at a depth
// of a micrometre and drops out of ODE's contact list at the slightest pitch, and one wheel
// missing for a step would yaw the robot.
constexpr double kGripHeight = 0.002;
// How far a wheel-body robot settles into the carpet, m: ODE lets a resting contact sink through
// the world's contact layer (contact_surface_layer: 0.5 mm by default and in every shipped world)
// before pushing back, and the omni drive's wheel contacts drift down through it within seconds
// (the robot comes to rest 0.5 mm low). The one-body robot's four supports on one rigid body
// would creep through it at a micrometre a second, so they are placed this much higher: the
// robot drops into the same place in its first 10 ms. The dribbler's reach into the ball is
// tuned to that height (a rigid robot 0.5 mm high does not draw in a ball 2 mm off its face).
constexpr double kSettle = 0.0005;
// Largest yaw gain of the wheel servos (1 reaches the target in one step, 2 oscillates forever).
constexpr double kMaxYawGain = 1.8;
// Layout of SaveState's bytes: bump when they change.
constexpr std::uint32_t kStateLayout = 1;

class OmniForceDrive final : public ubersim::Drive {
 public:
  void Configure(ubersim::RobotContext& ctx) override {
    ctx_ = &ctx;
    const ubersim::ParamView& p = ctx.Params();
    const ubersim::RobotBodyInfo& body = ctx.BodyInfo();
    wheel_radius_ = p["wheel_radius"].AsDouble();
    const double width = p.GetDouble("wheel_width", 0.01);
    // wheel_mass is accepted and unused: there are no wheel bodies (the schema says so).
    distance_ = p.Has("wheel_distance") ? p["wheel_distance"].AsDouble() : body.radius - width;
    if (p.Has("motor")) {
      max_torque_ = p["motor"].GetDouble("max_torque", max_torque_);
      max_wheel_speed_ = p["motor"].GetDouble("max_speed", max_wheel_speed_);
    }
    if (p.Has("limits")) servo_.SetLimits(ubersim::ReadServoLimits(p["limits"], servo_.Limits()));
    watchdog_.SetTimeout(p.GetDouble("command_timeout", watchdog_.Timeout()));
    // The same surface as the omni drive's tyres: the world's table pair <name>|carpet, or the
    // two surfaces combined, decides the friction; the support contacts report it (below).
    ubersim::SurfaceMaterial surface;
    surface.name = "omni_wheel";
    surface.mu = 0.05;   // along the axle
    surface.mu2 = 0.8;   // along the rolling direction
    if (p.Has("surface")) {
      const ubersim::ParamView s = p["surface"];
      surface.name = s.GetString("name", surface.name);
      surface.mu = s.GetDouble("mu_axle", surface.mu);
      surface.mu2 = s.GetDouble("mu_roll", surface.mu2);
    }
    if (wheel_radius_ * 2 <= body.ground_clearance) {
      throw ubersim::PluginError("wheel_radius " + std::to_string(wheel_radius_) +
                                 " m leaves the wheels above the carpet (ground_clearance " +
                                 std::to_string(body.ground_clearance) + " m)");
    }

    ubersim::Body& chassis = ctx.Chassis();
    // The robot stands on the carpet at z = 0; the chassis origin (its centre of mass) is this high.
    const double chassis_z = chassis.GetPose().position.z();
    const ubersim::ParamView list = p["wheels"];
    wheels_.resize(list.Size());
    for (std::size_t i = 0; i < wheels_.size(); ++i) {
      Wheel& w = wheels_[i];
      const double angle = list.At(i)["angle_deg"].AsDouble() * M_PI / 180.0;
      const Vec3 radial(std::cos(angle), std::sin(angle), 0.0);
      w.tangent = Vec3(-std::sin(angle), std::cos(angle), 0.0);
      w.centre = radial * distance_ + Vec3(0, 0, wheel_radius_ - chassis_z);
      w.mu_axle = surface.mu;
      w.mu_roll = surface.mu2;
      // The support: a sphere of the wheel's radius at its centre (kSettle higher: see there)
      // touches the carpet at one point under the axle, as AddDrivenWheel's carpet contact does,
      // so the robot stands as high as on wheels. It pokes out of the shell (0.079 + 0.029 m >
      // 0.09 m on the modern robot), so it keeps only its carpet contacts; the ball, walls and
      // robots meet the chassis shell, as they would meet the shell around real wheels.
      ubersim::GeomSpec support;
      support.name = "wheel" + std::to_string(i);
      support.shape = ubersim::Shape::Sphere(wheel_radius_);
      support.offset.position = w.centre + Vec3(0, 0, kSettle);
      support.material = surface;
      support.scope = ubersim::ContactScope::kPlanesOnly;
      ubersim::Geom& geom = ctx.Node().AddGeom(support, &chassis);
      ctx.ObserveContacts(geom, [this, i](const ubersim::Contact& c, ubersim::SurfaceMaterial& s, bool& accept) {
        // Its scope lets only planes through; of those, the carpet (a wall could be a plane too).
        if (c.other->GetShape().plane_normal.z() < 0.9) {
          accept = false;
          return;
        }
        // `s` is the wheel-carpet surface the omni drive's tyre would get (table pair or the two
        // surfaces combined): its friction becomes the wheel's force limits…
        Wheel& w = wheels_[i];
        w.mu_axle = s.mu;
        w.mu_roll = s.mu2 < 0 ? s.mu : s.mu2;
        // …and the support itself carries the weight only: no friction, no bounce, no rolling
        // resistance (the wheel forces are the robot's only grip on the carpet).
        s.mu = 0.0;
        s.mu2 = -1.0;
        s.bounce = 0.0;
        s.rolling_friction = 0.0;
        s.slip = 0.0;
      });
    }
    // Wheel speeds from the robot's velocity, and a least-squares inverse for odometry (as omni).
    Eigen::MatrixXd m(wheels_.size(), 3);
    for (std::size_t i = 0; i < wheels_.size(); ++i) {
      m.row(static_cast<Eigen::Index>(i)) << wheels_[i].tangent.x(), wheels_[i].tangent.y(), distance_;
    }
    geometry_ = m / wheel_radius_;
    inverse_ = geometry_.completeOrthogonalDecomposition().pseudoInverse();
    wheel_targets_.setZero(static_cast<Eigen::Index>(wheels_.size()));
    // The wheels' yaw servo gain per step: their shares m/n at wheel_distance d over the
    // chassis' moment of inertia, a solid cylinder's m·R²/2, is 2·d²/R². At 2 or more each step
    // would overshoot by the whole error or more and the robot would spin up; wheels far out (d
    // close to or past R) get a softer servo instead.
    const double yaw_gain = 2.0 * distance_ * distance_ / (body.radius * body.radius);
    servo_scale_ = std::min(1.0, kMaxYawGain / yaw_gain);
  }

  void SetCommand(const ubersim::MoveCommand& command) override {
    if (const auto* w = std::get_if<ubersim::WheelSpeedCommand>(&command)) {
      if (w->wheel_speeds.size() != wheels_.size()) {
        throw ubersim::PluginError("wheel speed command has " + std::to_string(w->wheel_speeds.size()) +
                                   " speeds, this robot has " + std::to_string(wheels_.size()) + " wheels");
      }
    }
    command_ = command;
    watchdog_.Feed(ctx_->SimTime());
  }

  // What the encoders would read: each wheel turns with its contact point's speed along the
  // rolling direction (a wheel with no inertia never slips against its own contact).
  ubersim::DriveFeedback Feedback() const override {
    ubersim::DriveFeedback f;
    const ubersim::Body& chassis = ctx_->Chassis();
    const ubersim::Pose pose = chassis.GetPose();
    const Eigen::Matrix3d rotation = pose.orientation.toRotationMatrix();
    f.wheel_speeds.reserve(wheels_.size());
    for (const Wheel& w : wheels_) {
      const Frame fr = WheelFrame(pose.position, rotation, w);
      f.wheel_speeds.push_back(chassis.PointVelocity(fr.contact).dot(fr.rolling) / wheel_radius_);
    }
    const Eigen::Vector3d v = inverse_ * Eigen::Map<const Eigen::VectorXd>(  // forward, left, angular
                                             f.wheel_speeds.data(), static_cast<Eigen::Index>(f.wheel_speeds.size()));
    f.local_velocity.linear = Vec3(v.x(), v.y(), 0.0);
    f.local_velocity.angular = Vec3(0.0, 0.0, v.z());
    return f;
  }

  void Reset() override {
    watchdog_.Reset();
    servo_.Reset();
  }

  // The servo loop's memory and each wheel's friction as its last contact resolved it (the next
  // step's wheel forces are limited by it before this step's contacts exist).
  std::string SaveState() const override {
    ubersim::StateWriter w(kStateLayout);
    w.Watchdog(watchdog_).Setpoint(servo_.Setpoint()).Move(command_).Int(static_cast<std::int64_t>(wheels_.size()));
    for (const Wheel& wheel : wheels_) w.Double(wheel.mu_roll).Double(wheel.mu_axle);
    return w.Take();
  }

  void RestoreState(std::string_view state) override {
    ubersim::StateReader r(state, kStateLayout, "omni_force drive");
    r.Watchdog(watchdog_);
    servo_.Set(r.Setpoint());
    command_ = r.Move();
    if (r.Int() != static_cast<std::int64_t>(wheels_.size())) {
      throw ubersim::PluginError("omni_force drive: saved state is of a robot with another number of wheels");
    }
    for (Wheel& wheel : wheels_) {
      wheel.mu_roll = r.Double();
      wheel.mu_axle = r.Double();
    }
    r.Finish();
  }

  void PreStep(const ubersim::StepInfo& step) override {
    Eigen::VectorXd& targets = wheel_targets_;  // wheel speeds, rad/s
    const bool fresh = watchdog_.Fresh(ctx_->SimTime());
    const auto* direct = fresh ? std::get_if<ubersim::WheelSpeedCommand>(&command_) : nullptr;
    if (direct) {
      // Direct wheel speeds bypass the velocity loop, as on the real robots.
      const Eigen::Map<const Eigen::VectorXd> speeds(direct->wheel_speeds.data(),
                                                     static_cast<Eigen::Index>(direct->wheel_speeds.size()));
      targets = speeds.cwiseMax(-max_wheel_speed_).cwiseMin(max_wheel_speed_);
      const Eigen::Vector3d v = inverse_ * speeds;
      servo_.Set({Eigen::Vector2d(v.x(), v.y()), v.z()});
    } else {
      const ubersim::PlanarVelocity& set = servo_.Step(fresh ? TargetLocal() : ubersim::PlanarVelocity{}, step.dt);
      targets.noalias() = geometry_ * Eigen::Vector3d(set.linear.x(), set.linear.y(), set.angular);
      // Keep the direction when a wheel would exceed its speed: scale all wheels together.
      const double peak = targets.cwiseAbs().maxCoeff();
      if (peak > max_wheel_speed_) targets *= max_wheel_speed_ / peak;
    }
    PushWheels(targets, step.dt);
  }

 private:
  // Where a wheel meets the carpet and its directions there (world frame).
  struct Frame {
    Vec3 contact;   // under the wheel centre, at the carpet
    Vec3 rolling;   // unit, in the carpet plane: where a positive wheel speed drives the robot
    Vec3 axle;      // unit, in the carpet plane, across the rolling direction
  };

  Frame WheelFrame(const Vec3& position, const Eigen::Matrix3d& rotation, const Wheel& w) const {
    const Vec3 up = Vec3::UnitZ();  // the carpet's normal
    Frame f;
    f.contact = position + rotation * w.centre - up * wheel_radius_;
    f.rolling = rotation * w.tangent;
    f.rolling -= up * up.dot(f.rolling);
    f.rolling.normalize();
    f.axle = up.cross(f.rolling);
    return f;
  }

  // Each wheel's motor and rollers push the chassis at the wheel's contact point. At the carpet,
  // not at the centre of mass: braking pitches the robot onto its front supports as a real one
  // pitches onto its front wheels (the rigid supports hold it level to within 1 mrad; tests).
  // The force that would reach the wheel's target in this step if it moved its share of the
  // robot is a stiff proportional servo. Summed over the wheels it never overshoots in
  // translation; in yaw the shares act at wheel_distance on a chassis with less moment of
  // inertia than they would have there, so it overshoots by yaw_gain_ - 1 of the error each step
  // (0.54 on the modern robot) and settles in a few steps (see Configure).
  void PushWheels(const Eigen::VectorXd& targets, double dt) {
    ubersim::Body& chassis = ctx_->Chassis();
    // One read of the chassis' state for all wheels; the wheels' forces are summed into one
    // force and one torque about the centre of mass (the same as applying each at its point).
    const ubersim::Pose pose = chassis.GetPose();
    const ubersim::Twist twist = chassis.GetTwist();
    const Eigen::Matrix3d rotation = pose.orientation.toRotationMatrix();
    const double n = static_cast<double>(wheels_.size());
    const double load = chassis.Mass() / n * ctx_->Gravity().norm();  // N: static, no load transfer
    const double share = chassis.Mass() / n * servo_scale_;            // kg each wheel moves
    const double motor_force = max_torque_ / wheel_radius_;     // N at the contact
    Vec3 force = Vec3::Zero(), torque = Vec3::Zero();
    for (std::size_t i = 0; i < wheels_.size(); ++i) {
      const Wheel& w = wheels_[i];
      const Frame fr = WheelFrame(pose.position, rotation, w);
      if (fr.contact.z() > kGripHeight) continue;  // a wheel in the air pushes nothing
      const Vec3 arm = fr.contact - pose.position;
      const Vec3 v = twist.linear + twist.angular.cross(arm);  // the chassis' velocity at the contact
      const double surface_speed = targets(static_cast<Eigen::Index>(i)) * wheel_radius_;
      const double drive_limit = std::min(motor_force, w.mu_roll * load);
      const double drive = std::clamp(share * (surface_speed - v.dot(fr.rolling)) / dt, -drive_limit, drive_limit);
      const double roller_limit = w.mu_axle * load;
      const double roller = std::clamp(-share * v.dot(fr.axle) / dt, -roller_limit, roller_limit);
      const Vec3 push = fr.rolling * drive + fr.axle * roller;
      force += push;
      torque += arm.cross(push);
    }
    chassis.AddForce(force);
    chassis.AddTorque(torque);
  }

  // The command as (forward, left, angular) in the robot frame, within the speed limits.
  ubersim::PlanarVelocity TargetLocal() const {
    ubersim::PlanarVelocity t;
    if (const auto* l = std::get_if<ubersim::LocalVelocityCommand>(&command_)) {
      t = {Eigen::Vector2d(l->forward, l->left), l->angular};
    } else if (const auto* g = std::get_if<ubersim::GlobalVelocityCommand>(&command_)) {
      const double yaw = ctx_->Chassis().GetPose().Yaw();
      const double c = std::cos(yaw), s = std::sin(yaw);
      t = {Eigen::Vector2d(c * g->x + s * g->y, -s * g->x + c * g->y), g->angular};
    }
    return servo_.ClampToLimits(t);
  }

  ubersim::RobotContext* ctx_ = nullptr;
  std::vector<Wheel> wheels_;  // sized once in Configure: the contact handlers hold indices
  Eigen::MatrixXd geometry_;   // wheel speeds (rad/s) = geometry_ · (forward, left, angular)
  Eigen::MatrixXd inverse_;    // (forward, left, angular) = inverse_ · wheel speeds
  Eigen::VectorXd wheel_targets_;  // this step's wheel speeds, rad/s (sized once: no allocation per step)
  double wheel_radius_ = 0.029;
  double distance_ = 0.08;
  double max_torque_ = 0.5;
  double max_wheel_speed_ = 150;
  double servo_scale_ = 1.0;   // of each wheel's share of the mass in its servo force (<1: wheels far out)
  ubersim::VelocityServo servo_;       // the (forward, left, angular) setpoint the wheels follow
  ubersim::CommandWatchdog watchdog_{0.1};
  ubersim::MoveCommand command_;
};

}  // namespace

UBERSIM_REGISTER_DRIVE(OmniForceDrive, "omni_force", "1.0.0", ubersim_plugin::kSchema)
