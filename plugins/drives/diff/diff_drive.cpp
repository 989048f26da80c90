// SPDX-License-Identifier: Apache-2.0
// diff: a differential drive, the ÜberSim paper's "DiffRobot".
//
// Two driven wheels, motorised contacts on the chassis (or, with `wheel_bodies: true`, bodies on
// motorised hinges) whose axles lie along the robot's lateral (y) axis, grip the carpet with
// isotropic friction; one or two ball casters, low-friction spheres
// fixed to the chassis, keep it level. The casters are spring-loaded (a soft contact): with four
// rigid supports ODE may hand nearly all the weight to the casters, and the wheels, unloaded,
// spin in place; springs leave the weight on the wheels and only resist pitching. A local servo loop turns the move command into a
// (forward, angular) setpoint limited in speed, acceleration and braking, and the setpoint into
// the two wheel speeds, as the robots' firmware does. A diff robot cannot move sideways: the
// lateral part of a command is dropped, with a rate-limited warning.
#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include <ubersim/ubersim.hpp>

#include "ubersim_plugin_schema.hpp"

namespace {

using ubersim::Vec3;

// Lateral speeds up to this are heading noise of a global command, not a request, m/s.
constexpr double kGlobalLateralTolerance = 0.01;
// At most one "lateral part dropped" warning per this much simulated time, s.
constexpr double kWarningInterval = 1.0;
// Layout of SaveState's bytes: bump when they change. 2: the wheels' rates.
constexpr std::uint32_t kStateLayout = 2;

// Warns about dropped lateral commands: the first at once, then at most one per interval, each
// saying how many were dropped since the previous warning.
class LateralWarning {
 public:
  void Dropped(ubersim::Log& log, double now, double lateral) {
    ++dropped_;
    if (warned_ && now - last_ < kWarningInterval) return;
    log.Warning("a differential drive cannot move sideways: lateral speed " + std::to_string(lateral) +
                " m/s dropped, following forward and angular speed only (" + std::to_string(dropped_) +
                " command(s) since the last warning)");
    warned_ = true;
    last_ = now;
    dropped_ = 0;
  }
  void Save(ubersim::StateWriter& w) const { w.Bool(warned_).Double(last_).Int(dropped_); }
  void Restore(ubersim::StateReader& r) {
    warned_ = r.Bool();
    last_ = r.Double();
    dropped_ = static_cast<int>(r.Int());
  }

 private:
  bool warned_ = false;
  double last_ = 0.0;
  int dropped_ = 0;
};

class DiffDrive final : public ubersim::Drive {
 public:
  void Configure(ubersim::RobotContext& ctx) override {
    ctx_ = &ctx;
    const ubersim::ParamView& p = ctx.Params();
    const ubersim::RobotBodyInfo& body = ctx.BodyInfo();
    wheel_radius_ = p["wheel_radius"].AsDouble();
    const double width = p.GetDouble("wheel_width", 0.01);
    const double mass = p.GetDouble("wheel_mass", 0.05);
    separation_ = p.Has("wheel_separation") ? p["wheel_separation"].AsDouble() : 2 * (body.radius - width);
    const double axle_x = p.GetDouble("axle_offset", 0.0);
    if (p.Has("motor")) {
      max_torque_ = p["motor"].GetDouble("max_torque", max_torque_);
      max_wheel_speed_ = p["motor"].GetDouble("max_speed", max_wheel_speed_);
      rotor_inertia_ = p["motor"].GetDouble("rotor_inertia", rotor_inertia_);
    }
    ubersim::ServoLimits limits;  // the 2003 robots' defaults (schema)
    limits.max_speed = 2.0;
    limits.max_accel = 2.0;
    limits.max_brake = 4.0;
    limits.max_angular_speed = 8.0;
    limits.max_angular_accel = 40.0;
    limits.max_angular_brake = 40.0;
    servo_.SetLimits(p.Has("limits") ? ubersim::ReadServoLimits(p["limits"], limits) : limits);
    watchdog_.SetTimeout(p.GetDouble("command_timeout", 0.1));
    if (wheel_radius_ * 2 <= body.ground_clearance) {
      throw p["wheel_radius"].Error("wheel_radius " + std::to_string(wheel_radius_) +
                                    " m leaves the wheels above the carpet (ground_clearance " +
                                    std::to_string(body.ground_clearance) + " m)");
    }
    ubersim::SurfaceMaterial tyre_surface;
    tyre_surface.name = "drive_wheel";
    tyre_surface.mu = 1.0;  // rubber on carpet
    if (p.Has("surface")) {
      tyre_surface.name = p["surface"].GetString("name", tyre_surface.name);
      tyre_surface.mu = p["surface"].GetDouble("mu", tyre_surface.mu);
    }
    ubersim::SurfaceMaterial caster_surface;
    caster_surface.name = "caster";
    caster_surface.mu = 0.02;
    if (p.Has("caster_surface")) {
      caster_surface.name = p["caster_surface"].GetString("name", caster_surface.name);
      caster_surface.mu = p["caster_surface"].GetDouble("mu", caster_surface.mu);
    }

    // The robot stands on the carpet at z = 0; the chassis origin (its centre of mass) is this high.
    const double chassis_z = ctx.Chassis().GetPose().position.z();
    const bool wheel_bodies = p.GetBool("wheel_bodies", false);
    // The casters are springs that leave the weight on the two wheels.
    const double load = 0.5 * (ctx.Chassis().Mass() + 2 * mass) * ctx.Gravity().norm();
    const char* names[2] = {"wheel_left", "wheel_right"};
    for (int i = 0; i < 2; ++i) {
      const double side = i == 0 ? 1.0 : -1.0;  // left wheel at +y
      ubersim::WheelSpec w;
      w.node_name = names[i];
      w.centre = Vec3(axle_x, side * 0.5 * separation_, wheel_radius_ - chassis_z);
      w.axle = Vec3::UnitY();  // both along +y: a positive rate rolls the robot forward (+x)
      w.radius = wheel_radius_;
      w.width = width;
      w.mass = mass;
      w.tyre = tyre_surface;
      w.holding_torque = max_torque_;
      w.rotor_inertia = rotor_inertia_;
      wheels_[i].emplace(ctx, w, wheel_bodies, load);
    }
    AddCasters(ctx, p, caster_surface, chassis_z);
  }

  void SetCommand(const ubersim::MoveCommand& command) override {
    if (const auto* w = std::get_if<ubersim::WheelSpeedCommand>(&command)) {
      if (w->wheel_speeds.size() != 2) {
        throw ubersim::PluginError("wheel speed command has " + std::to_string(w->wheel_speeds.size()) +
                                   " speeds, this robot has 2 wheels (left, right)");
      }
    }
    const double now = ctx_->SimTime();
    if (const auto* l = std::get_if<ubersim::LocalVelocityCommand>(&command)) {
      if (l->left != 0.0) lateral_warning_.Dropped(ctx_->Logger(), now, l->left);
    } else if (const auto* g = std::get_if<ubersim::GlobalVelocityCommand>(&command)) {
      const double lateral = ToLocal(*g).y();
      if (std::abs(lateral) > kGlobalLateralTolerance) lateral_warning_.Dropped(ctx_->Logger(), now, lateral);
    }
    command_ = command;
    watchdog_.Feed(now);
  }

  ubersim::DriveFeedback Feedback() const override {
    ubersim::DriveFeedback f;
    const double left = wheels_[0]->Rate(), right = wheels_[1]->Rate();
    f.wheel_speeds = {left, right};
    // Odometry: what the wheels say, assuming they roll without slipping.
    f.local_velocity.linear = Vec3(0.5 * wheel_radius_ * (left + right), 0.0, 0.0);
    f.local_velocity.angular = Vec3(0.0, 0.0, wheel_radius_ * (right - left) / separation_);
    return f;
  }

  void Reset() override {
    watchdog_.Reset();
    servo_.Reset();
  }

  // Put down moving (or at rest): the wheels roll with the chassis and the speed loop starts from
  // its velocity (forward and turning: a differential robot has no sideways).
  void Placed() override {
    ubersim::PlanarVelocity v = ubersim::LocalPlanarVelocity(ctx_->Chassis());
    v.linear.y() = 0.0;
    servo_.Set(v);
    const std::array<double, 2> rates = WheelRates(v);
    for (int i = 0; i < 2; ++i) wheels_[i]->Roll(rates[i]);
  }

  // The servo loop's memory, the step length the casters' contacts use, and the warning's pace.
  std::string SaveState() const override {
    ubersim::StateWriter w(kStateLayout);
    w.Watchdog(watchdog_).Setpoint(servo_.Setpoint()).Move(command_).Double(dt_);
    lateral_warning_.Save(w);
    for (const auto& wheel : wheels_) w.Double(wheel->Rate());
    return w.Take();
  }

  void RestoreState(std::string_view state) override {
    ubersim::StateReader r(state, kStateLayout, "diff drive");
    r.Watchdog(watchdog_);
    servo_.Set(r.Setpoint());
    command_ = r.Move();
    dt_ = r.Double();
    lateral_warning_.Restore(r);
    for (auto& wheel : wheels_) {
      const double rate = r.Double();
      if (!wheel->WheelBody()) wheel->Roll(rate);  // a wheel body's spin is the kernel's to restore
    }
    r.Finish();
  }

  void PreStep(const ubersim::StepInfo& step) override {
    dt_ = step.dt;  // the casters' contacts of this step use it
    SetWheelMotors(step);
    for (auto& wheel : wheels_) wheel->Step(step.dt);
  }

 private:
  // This step's wheel motors: the direct wheel speeds of a fresh command, else the servo loop's.
  void SetWheelMotors(const ubersim::StepInfo& step) {
    const bool fresh = watchdog_.Fresh(ctx_->SimTime());
    if (fresh) {
      if (const auto* w = std::get_if<ubersim::WheelSpeedCommand>(&command_)) {
        // Direct wheel speeds bypass the velocity loop, as on the real robots.
        const double left = std::clamp(w->wheel_speeds[0], -max_wheel_speed_, max_wheel_speed_);
        const double right = std::clamp(w->wheel_speeds[1], -max_wheel_speed_, max_wheel_speed_);
        wheels_[0]->SetMotor(left, max_torque_);
        wheels_[1]->SetMotor(right, max_torque_);
        servo_.Set({Eigen::Vector2d(0.5 * wheel_radius_ * (left + right), 0.0),
                    wheel_radius_ * (right - left) / separation_});
        return;
      }
    }
    const ubersim::PlanarVelocity& set = servo_.Step(fresh ? TargetLocal() : ubersim::PlanarVelocity{}, step.dt);
    auto [left, right] = WheelRates(set);
    // Keep the curvature when a wheel would exceed its speed: scale both together.
    const double peak = std::max(std::abs(left), std::abs(right));
    if (peak > max_wheel_speed_) {
      left *= max_wheel_speed_ / peak;
      right *= max_wheel_speed_ / peak;
    }
    wheels_[0]->SetMotor(left, max_torque_);
    wheels_[1]->SetMotor(right, max_torque_);
  }

  void AddCasters(ubersim::RobotContext& ctx, const ubersim::ParamView& p,
                  const ubersim::SurfaceMaterial& surface, double chassis_z) {
    struct Caster { double x, radius; };
    std::vector<Caster> casters = {{0.06, 0.01}, {-0.06, 0.01}};
    if (p.Has("casters")) {
      casters.clear();
      const ubersim::ParamView list = p["casters"];
      for (std::size_t i = 0; i < list.Size(); ++i) {
        casters.push_back({list.At(i)["x"].AsDouble(), list.At(i).GetDouble("radius", 0.01)});
      }
    }
    caster_stiffness_ = p.GetDouble("caster_stiffness", caster_stiffness_);
    caster_damping_ = p.GetDouble("caster_damping", caster_damping_);
    ubersim::Body& chassis = ctx.Chassis();
    for (std::size_t i = 0; i < casters.size(); ++i) {
      ubersim::GeomSpec ball;
      ball.name = "caster" + std::to_string(i);
      ball.shape = ubersim::Shape::Sphere(casters[i].radius);
      ball.offset.position = Vec3(casters[i].x, 0.0, casters[i].radius - chassis_z);
      ball.material = surface;
      // Only the carpet: a caster hides under the chassis, nothing else should reach it.
      ball.scope = ubersim::ContactScope::kPlanesOnly;
      ubersim::Geom& g = ctx.Node().AddGeom(ball, &chassis);
      ctx.ObserveContacts(g, [this](const ubersim::Contact&, ubersim::SurfaceMaterial& s, bool&) {
        // ODE's contact as a spring k and damper d over a step h: ERP = hk/(hk+d), CFM = 1/(hk+d).
        const double hk = dt_ * caster_stiffness_;
        s.soft_erp = hk / (hk + caster_damping_);
        s.soft_cfm = 1.0 / (hk + caster_damping_);
      });
    }
  }

  // A global command's velocity in the robot frame (forward, left), m/s.
  Eigen::Vector2d ToLocal(const ubersim::GlobalVelocityCommand& g) const {
    return ubersim::ToRobotFrame(ubersim::HeadingOf(ctx_->Chassis().GetPose().orientation), g.x, g.y);
  }

  // The wheel speeds, left then right (rad/s), that drive the robot at `v` (forward and turning).
  std::array<double, 2> WheelRates(const ubersim::PlanarVelocity& v) const {
    const double half_track_speed = 0.5 * v.angular * separation_;
    return {(v.linear.x() - half_track_speed) / wheel_radius_, (v.linear.x() + half_track_speed) / wheel_radius_};
  }

  // The command as (forward, 0, angular) in the robot frame, within the speed limits; the
  // lateral part, which a diff robot cannot follow, is dropped.
  ubersim::PlanarVelocity TargetLocal() const {
    ubersim::PlanarVelocity t = ubersim::CommandedVelocity(command_, ctx_->Chassis());
    t.linear.y() = 0.0;
    return servo_.ClampToLimits(t);
  }

  ubersim::RobotContext* ctx_ = nullptr;
  std::optional<ubersim::DrivenWheel> wheels_[2];  // left (+y), right
  double wheel_radius_ = 0.03;
  double separation_ = 0.14;       // between the wheels' contact points, m
  double max_torque_ = 0.3;        // N·m
  double max_wheel_speed_ = 100;   // rad/s
  double rotor_inertia_ = 0;       // kg·m², reflected to the wheel
  double caster_stiffness_ = 10000;  // N/m
  double caster_damping_ = 100;      // N·s/m
  double dt_ = 0.001;               // s, the step being run
  ubersim::VelocityServo servo_;   // (forward, 0, angular) setpoint the wheels follow
  ubersim::CommandWatchdog watchdog_{0.1};
  ubersim::MoveCommand command_;
  LateralWarning lateral_warning_;
};

}  // namespace

UBERSIM_REGISTER_DRIVE(DiffDrive, "diff", "1.0.0", ubersim_plugin::kSchema)
