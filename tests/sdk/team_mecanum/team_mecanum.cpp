// SPDX-License-Identifier: Apache-2.0
// team_mecanum: what a team writes for next year's robot, from docs/plugins.md and the installed
// SDK only. Four wheel bodies on motorised hinges at the corners; each wheel's rollers sit at 45°
// to its axle (WheelSpec::roller_turn), so the carpet grips it only across its rollers. The
// firmware's servo loop (the SDK's VelocityServo) ramps the command; the wheel speeds follow from
// where each wheel sits and which way its rollers grip.
#include <array>
#include <memory>
#include <cmath>
#include <variant>

#include <Eigen/Dense>
#include <ubersim/ubersim.hpp>

#include "ubersim_plugin_schema.hpp"

namespace {

using ubersim::Vec3;

class TeamMecanum final : public ubersim::Drive {
 public:
  void Configure(ubersim::RobotContext& ctx) override {
    ctx_ = &ctx;
    const ubersim::ParamView& p = ctx.Params();
    const double a = p["half_length"].AsDouble();
    const double b = p["half_track"].AsDouble();
    radius_ = p["wheel_radius"].AsDouble();
    max_torque_ = p.GetDouble("max_torque", 0.3);
    max_wheel_speed_ = p.GetDouble("max_wheel_speed", 150.0);
    if (p.Has("limits")) servo_.SetLimits(ubersim::ReadServoLimits(p["limits"], servo_.Limits()));
    if (radius_ * 2 <= ctx.BodyInfo().ground_clearance) {
      throw ubersim::PluginError("wheel_radius leaves the wheels above the carpet");
    }

    // Front left, rear left, rear right, front right; rollers in an X seen from above.
    const std::array<Vec3, 4> corners = {Vec3(a, b, 0), Vec3(-a, b, 0), Vec3(-a, -b, 0), Vec3(a, -b, 0)};
    const std::array<double, 4> roller = {-M_PI / 4, M_PI / 4, -M_PI / 4, M_PI / 4};
    ubersim::SurfaceMaterial tyre;
    tyre.name = "team_mecanum_roller";
    tyre.mu = 0.05;  // along the rollers' free direction
    tyre.mu2 = 0.8;  // across it: the grip
    const double chassis_z = ctx.Chassis().GetPose().position.z();  // its origin above the carpet
    // Each wheel carries a quarter of the robot standing, its wheels included.
    const double load = (ctx.Chassis().Mass() + 4 * ubersim::WheelSpec{}.mass) * ctx.Gravity().norm() / 4;
    for (std::size_t i = 0; i < 4; ++i) {
      ubersim::WheelSpec spec;
      spec.node_name = "wheel" + std::to_string(i);
      spec.centre = corners[i] + Vec3(0, 0, radius_ - chassis_z);
      spec.axle = Vec3::UnitY();  // a positive rate rolls the wheel forward (axle × z = x)
      spec.radius = radius_;
      spec.tyre = tyre;
      spec.rollers_along_axle = true;
      spec.roller_turn = roller[i];
      spec.holding_torque = max_torque_;
      spec.tyre_shielded = ubersim::ShellShieldsWheel(ctx.BodyInfo(), ctx.BallRadius(), spec);
      wheels_[i] = ubersim::AddContactWheel(ctx, spec, load);  // a motorised contact on the chassis
      // The rollers pass on the contact's motion along their grip direction only: a turn of
      // the wheel moves the contact r·ω forward, of which cos(roller) lies along the grip.
      const Vec3 grip = Eigen::AngleAxisd(roller[i], Vec3::UnitZ()) * Vec3::UnitX();
      const double lever = corners[i].x() * grip.y() - corners[i].y() * grip.x();
      const double share = std::cos(roller[i]) * radius_;
      to_wheels_.row(static_cast<Eigen::Index>(i)) << grip.x() / share, grip.y() / share, lever / share;
    }
    to_chassis_ = to_wheels_.completeOrthogonalDecomposition().pseudoInverse();
  }

  void SetCommand(const ubersim::MoveCommand& command) override {
    if (std::holds_alternative<ubersim::WheelSpeedCommand>(command)) {
      throw ubersim::PluginError("team_mecanum takes velocities, not wheel speeds");
    }
    command_ = command;
    watchdog_.Feed(ctx_->SimTime());
  }

  ubersim::DriveFeedback Feedback() const override {
    ubersim::DriveFeedback f;
    Eigen::Vector4d w;
    for (std::size_t i = 0; i < 4; ++i) w(static_cast<Eigen::Index>(i)) = wheels_[i]->Rate();
    f.wheel_speeds.assign(w.data(), w.data() + 4);
    const Eigen::Vector3d v = to_chassis_ * w;
    f.local_velocity.linear = Vec3(v.x(), v.y(), 0.0);
    f.local_velocity.angular = Vec3(0.0, 0.0, v.z());
    return f;
  }

  void Reset() override {
    watchdog_.Reset();
    servo_.Reset();
  }

  void PreStep(const ubersim::StepInfo& step) override {
    ubersim::PlanarVelocity target;
    if (watchdog_.Fresh(ctx_->SimTime())) target = ubersim::CommandedVelocity(command_, ctx_->Chassis());
    const ubersim::PlanarVelocity& set = servo_.Step(servo_.ClampToLimits(target), step.dt);
    const Eigen::Vector4d w = to_wheels_ * Eigen::Vector3d(set.linear.x(), set.linear.y(), set.angular);
    const double peak = w.cwiseAbs().maxCoeff();
    const double scale = peak > max_wheel_speed_ ? max_wheel_speed_ / peak : 1.0;
    for (std::size_t i = 0; i < 4; ++i) {
      wheels_[i]->SetMotor(scale * w(static_cast<Eigen::Index>(i)), max_torque_);
      wheels_[i]->Step(step.dt);
    }
  }

 private:
  ubersim::RobotContext* ctx_ = nullptr;
  std::array<std::unique_ptr<ubersim::ContactWheel>, 4> wheels_;
  Eigen::Matrix<double, 4, 3> to_wheels_;   // wheel speeds (rad/s) from (forward, left, angular)
  Eigen::Matrix<double, 3, 4> to_chassis_;  // and back: odometry
  double radius_ = 0.029;
  double max_torque_ = 0.3;
  double max_wheel_speed_ = 150.0;
  ubersim::VelocityServo servo_;
  ubersim::CommandWatchdog watchdog_{0.1};
  ubersim::MoveCommand command_;
};

}  // namespace

UBERSIM_REGISTER_DRIVE(TeamMecanum, "team_mecanum", "0.3.0", ubersim_plugin::kSchema)
