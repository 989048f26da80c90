// SPDX-License-Identifier: Apache-2.0
// omni and mecanum: omni-directional drives with any number of roller wheels at any angles.
//
// Each wheel is a motorised contact on the chassis (ubersim::ContactWheel), or, when the model
// asks (`wheel_bodies: true`), a body on a motorised hinge. Its contact with the carpet grips
// across its rollers and slides freely along them, which ODE models as directional friction: the
// geometry's friction axis is the axle, turned by the rollers' angle (0 for an omni wheel, whose
// rollers let it slide along the axle; ±45° for a mecanum wheel). A contact wheel's turning is
// the contact's surface velocity: the carpet pushes the chassis directly, so two solver sweeps
// hold a robot standing and braking where light wheel bodies between the chassis and the carpet
// let it sag and creep (docs/plugins.md). A local servo loop turns the move command into a
// velocity setpoint limited in speed, acceleration and braking, and the setpoint into wheel
// speeds through the wheel geometry, as the robots' firmware does. The same source builds both
// plugins (UBERSIM_ROLLER_DRIVE_ID): mecanum differs in its schema, which asks for each wheel's
// axle and roller angle.
#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include <Eigen/Dense>
#include <ubersim/ubersim.hpp>

#include "ubersim_plugin_schema.hpp"

namespace {

using ubersim::Vec3;

// Layout of SaveState's bytes: bump when they change. 2: the gyro loop's heading error; 3: the
// contact wheels' rates.
constexpr std::uint32_t kStateLayout = 3;

#ifndef UBERSIM_ROLLER_DRIVE_ID
#define UBERSIM_ROLLER_DRIVE_ID "omni"
#endif

struct Wheel {
  double angle = 0;            // rad, position from forward, counter-clockwise
  Vec3 position;               // contact point in the robot frame (z = 0)
  Vec3 grip;                   // the direction the rollers grip in (the rolling direction for omni)
  double grip_share = 1.0;     // cos of the roller angle: how much of a wheel turn moves along `grip`
  bool on_circle = true;       // an omni wheel with an inward axle: its lever is the wheel distance
  std::optional<ubersim::DrivenWheel> driven;  // a contact on the chassis, or a body (wheel_bodies)
};

class OmniDrive final : public ubersim::Drive {
 public:
  void Configure(ubersim::RobotContext& ctx) override {
    ctx_ = &ctx;
    const ubersim::ParamView& p = ctx.Params();
    const ubersim::RobotBodyInfo& body = ctx.BodyInfo();
    wheel_radius_ = p["wheel_radius"].AsDouble();
    const double width = p.GetDouble("wheel_width", 0.01);
    const double mass = p.GetDouble("wheel_mass", 0.05);
    distance_ = p.Has("wheel_distance") ? p["wheel_distance"].AsDouble() : body.radius - width;
    if (p.Has("motor")) {
      max_torque_ = p["motor"].GetDouble("max_torque", max_torque_);
      max_wheel_speed_ = p["motor"].GetDouble("max_speed", max_wheel_speed_);
      rotor_inertia_ = p["motor"].GetDouble("rotor_inertia", rotor_inertia_);
    }
    if (p.Has("limits")) servo_.SetLimits(ubersim::ReadServoLimits(p["limits"], servo_.Limits()));
    watchdog_.SetTimeout(p.GetDouble("command_timeout", watchdog_.Timeout()));
    gyro_ = ubersim::GyroRateLoop(p.GetDouble("heading_hold", 10.0));
    const bool wheel_bodies = p.GetBool("wheel_bodies", false);
    ubersim::SurfaceMaterial surface;
    surface.name = std::string(UBERSIM_ROLLER_DRIVE_ID) + "_wheel";
    surface.mu = 0.05;   // along the friction axis = the axle
    surface.mu2 = 0.8;   // across it = the rolling direction
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

    // The robot stands on the carpet at z = 0; the chassis origin (its centre of mass) is this high.
    const double chassis_z = ctx.Chassis().GetPose().position.z();
    const ubersim::ParamView list = p["wheels"];
    // What each wheel carries standing: the robot's weight, its wheels included, over its wheels.
    const double load = (ctx.Chassis().Mass() + mass * static_cast<double>(list.Size())) * ctx.Gravity().norm() /
                        static_cast<double>(list.Size());
    for (std::size_t i = 0; i < list.Size(); ++i) {
      Wheel w;
      const ubersim::ParamView entry = list.At(i);
      w.angle = entry["angle_deg"].AsDouble() * M_PI / 180.0;
      const Vec3 radial(std::cos(w.angle), std::sin(w.angle), 0.0);
      // The axle points inward unless given: a positive rate then rolls the wheel along
      // axle × z (counter-clockwise about the robot's centre for an inward axle).
      const bool own_axle = entry.Has("axle_deg");
      const double axle_angle = own_axle ? entry["axle_deg"].AsDouble() * M_PI / 180.0 : 0.0;
      const Vec3 axle = own_axle ? Vec3(std::cos(axle_angle), std::sin(axle_angle), 0.0) : Vec3(-radial);
      const Vec3 rolling = axle.cross(Vec3::UnitZ());
      const double roller = entry.GetDouble("roller_deg", 0.0) * M_PI / 180.0;
      if (std::cos(roller) < 0.1) throw ubersim::PluginError("wheel " + std::to_string(i) + ": roller_deg must be within ±84°");
      w.position = radial * distance_;
      w.grip = Eigen::AngleAxisd(roller, Vec3::UnitZ()) * rolling;
      w.grip_share = std::cos(roller);
      w.on_circle = !own_axle && roller == 0.0;
      ubersim::WheelSpec spec;
      spec.node_name = "wheel" + std::to_string(i);
      spec.centre = w.position + Vec3(0, 0, wheel_radius_ - chassis_z);
      spec.axle = axle;
      spec.roller_turn = roller;
      spec.radius = wheel_radius_;
      spec.width = width;
      spec.mass = mass;
      spec.tyre = surface;
      spec.rollers_along_axle = true;  // mu along the rollers' free direction, mu2 across it
      spec.holding_torque = max_torque_;
      spec.rotor_inertia = rotor_inertia_;
      spec.tyre_shielded = ubersim::ShellShieldsWheel(body, ctx.BallRadius(), spec);
      w.driven.emplace(ctx, spec, wheel_bodies, load);
      wheels_.push_back(std::move(w));
    }
    // A wheel turning at ω moves its contact by r·ω along its rolling direction; the rollers pass
    // on only the part along `grip`: ω = v_contact·grip / (r·cos roller), v_contact = v + ω_z × p.
    // For an omni wheel (grip = rolling direction, roller 0) that is v·t/r + ω_z·distance/r.
    Eigen::MatrixXd m(wheels_.size(), 3);
    for (std::size_t i = 0; i < wheels_.size(); ++i) {
      const Wheel& w = wheels_[i];
      const double lever = w.on_circle ? distance_ : w.position.x() * w.grip.y() - w.position.y() * w.grip.x();
      m.row(static_cast<Eigen::Index>(i)) << w.grip.x() / w.grip_share, w.grip.y() / w.grip_share, lever / w.grip_share;
    }
    // Least-squares inverse of the wheel geometry, for odometry feedback.
    geometry_ = m / wheel_radius_;
    inverse_ = geometry_.completeOrthogonalDecomposition().pseudoInverse();
    wheel_targets_.setZero(static_cast<Eigen::Index>(wheels_.size()));
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

  ubersim::DriveFeedback Feedback() const override {
    ubersim::DriveFeedback f;
    f.wheel_speeds.reserve(wheels_.size());
    for (const Wheel& w : wheels_) f.wheel_speeds.push_back(w.driven->Rate());
    const Eigen::Vector3d v = inverse_ * Eigen::Map<const Eigen::VectorXd>(  // forward, left, angular
                                             f.wheel_speeds.data(), static_cast<Eigen::Index>(f.wheel_speeds.size()));  // forward, left, angular
    f.local_velocity.linear = Vec3(v.x(), v.y(), 0.0);
    f.local_velocity.angular = Vec3(0.0, 0.0, v.z());
    return f;
  }

  void Reset() override {
    watchdog_.Reset();
    servo_.Reset();
    gyro_.Reset();
  }

  // Put down moving (or at rest): the wheels roll with the chassis and the speed loop starts from
  // its velocity, as a robot's firmware would find it.
  void Placed() override {
    const ubersim::PlanarVelocity v = ubersim::LocalPlanarVelocity(ctx_->Chassis());
    servo_.Set(v);
    gyro_.Reset();
    wheel_targets_.noalias() = geometry_ * Eigen::Vector3d(v.linear.x(), v.linear.y(), v.angular);
    for (std::size_t i = 0; i < wheels_.size(); ++i) {
      wheels_[i].driven->Roll(wheel_targets_(static_cast<Eigen::Index>(i)));
    }
  }

  // The servo loop's memory and the wheels' rates (a wheel body's is the kernel's to save too:
  // restoring it rolls the body as it already rolls).
  std::string SaveState() const override {
    ubersim::StateWriter w(kStateLayout);
    w.Watchdog(watchdog_).Setpoint(servo_.Setpoint()).Move(command_).Double(gyro_.HeadingError());
    for (const Wheel& wheel : wheels_) w.Double(wheel.driven->Rate());
    return w.Take();
  }

  void RestoreState(std::string_view state) override {
    ubersim::StateReader r(state, kStateLayout, "omni drive");
    r.Watchdog(watchdog_);
    servo_.Set(r.Setpoint());
    command_ = r.Move();
    gyro_.SetHeadingError(r.Double());
    for (Wheel& wheel : wheels_) {
      const double rate = r.Double();
      if (!wheel.driven->WheelBody()) wheel.driven->Roll(rate);
    }
    r.Finish();
  }

  void PreStep(const ubersim::StepInfo& step) override {
    // The chassis as the step starts: the servo's heading and every wheel's motor read this pose.
    const ubersim::Pose pose = ctx_->Chassis().GetPose();
    SetWheelMotors(step, pose);
    for (Wheel& w : wheels_) w.driven->Step(step.dt, pose);
  }

 private:
  // This step's wheel motors: the direct wheel speeds of a fresh command, else the servo loop's.
  void SetWheelMotors(const ubersim::StepInfo& step, const ubersim::Pose& pose) {
    const bool fresh = watchdog_.Fresh(ctx_->SimTime());
    if (fresh) {
      if (const auto* w = std::get_if<ubersim::WheelSpeedCommand>(&command_)) {
        // Direct wheel speeds bypass the velocity loop, as on the real robots.
        for (std::size_t i = 0; i < wheels_.size(); ++i) {
          wheels_[i].driven->SetMotor(std::clamp(w->wheel_speeds[i], -max_wheel_speed_, max_wheel_speed_), max_torque_);
        }
        const Eigen::Vector3d v = inverse_ * Eigen::Map<const Eigen::VectorXd>(
                                                 w->wheel_speeds.data(), static_cast<Eigen::Index>(w->wheel_speeds.size()));
        servo_.Set({Eigen::Vector2d(v.x(), v.y()), v.z()});
        gyro_.Reset();
        return;
      }
    }
    const ubersim::PlanarVelocity& set =
        servo_.Step(fresh ? TargetLocal(ubersim::HeadingOf(pose.orientation)) : ubersim::PlanarVelocity{}, step.dt);
    // The firmware's gyro holds the heading the setpoint integrates to.
    const double spin = gyro_.Correct(set.angular, ctx_->Chassis().GetTwist().angular.z(), step.dt);
    // In the frame the robot turns to within the step: driving while turning, it keeps its course.
    const Eigen::Vector2d lin = ubersim::AheadOfTheTurn(set.linear, spin, step.dt);

    wheel_targets_.noalias() = geometry_ * Eigen::Vector3d(lin.x(), lin.y(), spin);
    // Keep the direction when a wheel would exceed its speed: scale all wheels together.
    const double peak = wheel_targets_.cwiseAbs().maxCoeff();
    const double scale = peak > max_wheel_speed_ ? max_wheel_speed_ / peak : 1.0;
    for (std::size_t i = 0; i < wheels_.size(); ++i) {
      wheels_[i].driven->SetMotor(scale * wheel_targets_(static_cast<Eigen::Index>(i)), max_torque_);
    }
  }

  // The command as (forward, left, angular) in the frame of a robot heading along `heading`
  // (unit), within the speed limits.
  ubersim::PlanarVelocity TargetLocal(const Eigen::Vector2d& heading) const {
    return servo_.ClampToLimits(ubersim::CommandedVelocity(command_, heading));
  }

  ubersim::RobotContext* ctx_ = nullptr;
  std::vector<Wheel> wheels_;
  Eigen::MatrixXd geometry_;   // wheel speeds (rad/s) = geometry_ · (forward, left, angular)
  Eigen::MatrixXd inverse_;    // (forward, left, angular) = inverse_ · wheel speeds
  Eigen::VectorXd wheel_targets_;  // this step's wheel speeds, rad/s (sized once: no allocation per step)
  double wheel_radius_ = 0.029;
  double distance_ = 0.08;
  double max_torque_ = 0.5;
  double max_wheel_speed_ = 150;
  double rotor_inertia_ = 0;  // kg·m², reflected to the wheel
  ubersim::VelocityServo servo_;       // the (forward, left, angular) setpoint the wheels follow
  ubersim::GyroRateLoop gyro_;         // heading hold on the measured turn rate
  ubersim::CommandWatchdog watchdog_{0.1};
  ubersim::MoveCommand command_;
};

}  // namespace

UBERSIM_REGISTER_DRIVE(OmniDrive, UBERSIM_ROLLER_DRIVE_ID, "1.0.0", ubersim_plugin::kSchema)
