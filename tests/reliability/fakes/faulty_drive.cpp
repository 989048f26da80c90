// SPDX-License-Identifier: Apache-2.0
// A drive that misbehaves on purpose, in the way its `fault` parameter names, at step `at_step`:
//   none                    a working drive (pushes the chassis toward the command, spins a wheel)
//   configure_throws        builds its wheel, then Configure throws std::out_of_range (a bug)
//   configure_refuses       Configure throws PluginError (refuses its parameters: a model error)
//   prestep_throws          PreStep throws std::runtime_error
//   command_throws          SetCommand throws std::logic_error (a bug)
//   command_refuses         SetCommand throws PluginError (refuses the command)
//   nan_force               PreStep leaves the chassis an infinite force and a NaN torque, through
//                           the SDK's finite-only calls (1e308 N twice; a far-off point: inf - inf)
//   contact_nan             its wheel's contact handler sets the friction to NaN
//   contact_throws          its wheel's contact handler throws
//   contact_huge            its wheel's contact handler sets two values finite but so large their
//                           sum is not (no fault: the guard's one-sum test must look closer)
//   segfault                PreStep raises SIGSEGV (the crash report's test)
#include <csignal>
#include <limits>
#include <stdexcept>
#include <string>

#include <ubersim/ubersim.hpp>

namespace {

using ubersim::Vec3;

class FaultyDrive final : public ubersim::Drive {
 public:
  void Configure(ubersim::RobotContext& ctx) override {
    ctx_ = &ctx;
    fault_ = ctx.Params().GetString("fault", "none");
    at_step_ = ctx.Params().GetInt("at_step", 0);
    if (fault_ == "configure_refuses") throw ubersim::PluginError("gain must be positive (a parameter refused)");
    // A wheel on a motorised hinge under the chassis' front: its motor must stop when the
    // drive fails.
    ubersim::WheelSpec spec;
    spec.node_name = "wheel";
    // Its axle 1 mm low: the wheel presses on the carpet, its contact handler called every step
    // (resting on it exactly, a solver that converges well leaves it a hair above).
    spec.centre = Vec3(0.05, 0.0, 0.029 - ctx.Chassis().GetPose().position.z());
    spec.axle = Vec3::UnitY();
    spec.radius = 0.03;
    spec.tyre.name = "faulty_tyre";
    spec.tyre.mu = 0.0;  // no grip: the wheel spins without moving the robot
    wheel_ = &ubersim::AddDrivenWheel(ctx, spec);
    wheel_->SetMotor(10.0, 0.1);
    ubersim::Geom* tyre = ctx.Node().FindChild("wheel")->FindGeom("carpet_contact");
    ctx.ObserveContacts(*tyre, [this](const ubersim::Contact&, ubersim::SurfaceMaterial& s, bool&) {
      if (!active_) return;
      if (fault_ == "contact_nan") s.mu = std::numeric_limits<double>::quiet_NaN();
      if (fault_ == "contact_throws") throw std::runtime_error("contact handler bug");
      if (fault_ == "contact_huge") {
        s.mu = 1e308;  // grips without a limit (ODE takes dInfinity too)
        s.bounce_velocity = 1e308;  // read only with a bounce, and there is none
      }
    });
    if (fault_ == "configure_throws") throw std::out_of_range("wheel index 4 of 4");
  }

  void SetCommand(const ubersim::MoveCommand& command) override {
    if (fault_ == "command_throws") throw std::logic_error("command handler bug");
    if (fault_ == "command_refuses") throw ubersim::PluginError("faulty_drive takes no commands today");
    if (const auto* l = std::get_if<ubersim::LocalVelocityCommand>(&command)) target_ = Vec3(l->forward, l->left, 0);
  }

  ubersim::DriveFeedback Feedback() const override { return {}; }

  void PreStep(const ubersim::StepInfo& step) override {
    active_ = step.step >= at_step_;
    ubersim::Body& c = ctx_->Chassis();
    if (active_) {
      if (fault_ == "prestep_throws") throw std::runtime_error("motor controller exploded");
      if (fault_ == "nan_force") {
        c.AddForce(Vec3(1e308, 0, 0));
        c.AddForce(Vec3(1e308, 0, 0));
        c.AddForceAtPoint(Vec3(1e308, 1e308, 0), c.GetPose().position + Vec3(1e10, 1e10, 0));
        return;
      }
      if (fault_ == "segfault") std::raise(SIGSEGV);
    }
    const Vec3 target = c.GetPose().orientation * target_;
    Vec3 error = target - c.GetTwist().linear;
    error.z() = 0;
    c.AddForce(error * 30.0 * c.Mass());
    wheel_->SetMotor(10.0, 0.1);
  }

  // The command it follows: enough to show a restored drive goes on as the saved one.
  std::string SaveState() const override {
    return ubersim::StateWriter(1).Double(target_.x()).Double(target_.y()).Take();
  }
  void RestoreState(std::string_view state) override {
    ubersim::StateReader r(state, 1, "faulty_drive");
    target_.x() = r.Double();
    target_.y() = r.Double();
    r.Finish();
  }

 private:
  ubersim::RobotContext* ctx_ = nullptr;
  ubersim::Joint* wheel_ = nullptr;
  std::string fault_;
  std::int64_t at_step_ = 0;
  bool active_ = false;
  Vec3 target_ = Vec3::Zero();
};

}  // namespace

UBERSIM_REGISTER_DRIVE(FaultyDrive, "faulty_drive", "1.0", R"({"type": "object"})")
