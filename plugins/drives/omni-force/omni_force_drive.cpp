// SPDX-License-Identifier: Apache-2.0
// omni_force: the omni drive as one rigid body per robot, for speed.
//
// The omni drive makes a body per wheel on a motorised hinge and lets ODE's contact friction move
// the robot. This drive makes no wheel bodies and no wheel contacts. Every step each wheel's force
// on the carpet is computed and applied to the chassis, as the ER-Force simulator drives its robots:
//
//   - along the rolling direction the wheel's motor is a velocity servo against the carpet: it
//     pushes the contact point toward the wheel's surface speed ω·r with the force that would get
//     there in one step if it moved its share of the robot (mass / wheel count), at most the
//     motor's max_torque / r and at most mu_roll times its share of the weight;
//   - along the axle the free rollers resist sliding with at most mu_axle times that share.
//
// The wheels also hold the robot up, as rigid wheels on a flat carpet would, without a contact:
// while the robot is down (its centre of mass at most kGripHeight above where it rests) the drive
// carries its weight during the step and after it puts the chassis back level at its resting
// height, with no vertical or tilting speed. What a collision did to those is taken by the carpet:
// the robot does not tilt, bounce or lift off (nor does a real one: its centre of mass is 5 cm up
// on an 18 cm footprint). Lifted higher (a teleport into the air) it falls until it lands. Four
// support contacts on the carpet instead (as before) were 40 % of a Div A step's work: speed is
// what this drive exists for.
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

// At most this many wheels (the schema's maxItems): the per-step vectors and matrices live on the
// stack at this capacity, no allocation per step.
constexpr int kMaxWheels = 8;
using WheelSpeeds = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxWheels, 1>;          // one per wheel
using WheelsToVelocity = Eigen::Matrix<double, 3, Eigen::Dynamic, 0, 3, kMaxWheels>;     // 3 × wheels

// The wheels' planar numbers (Wheel's), one array per number: the per-step loops read them
// lane by lane.
struct WheelColumns {
  double tangent_x[kMaxWheels] = {}, tangent_y[kMaxWheels] = {};
  double axle_x[kMaxWheels] = {}, axle_y[kMaxWheels] = {};
  double roll_lever[kMaxWheels] = {}, axle_lever[kMaxWheels] = {};
};

struct Wheel {
  Vec3 centre;        // wheel centre in the chassis frame (origin at the centre of mass), m
  Vec3 tangent;       // rolling direction in the robot frame (counter-clockwise)
  // In the carpet plane, robot frame: the axle (up × tangent) and each direction's lever arm
  // about the vertical through the centre of mass (centre × direction), m.
  double axle_x = 0, axle_y = 0;
  double roll_lever = 0, axle_lever = 0;
};

// sin and cos of a turn of at most 0.1 rad (a step's turn: 12 rad/s for 5 ms is 0.06) by their
// series to the last bit (the first term left out is below 3e-19 of the result); std::sin and
// std::cos beyond. A libm call was a tenth of a robot's drive work per step.
void SinCosOfSmallTurn(double a, double& s, double& c) {
  if (!(std::abs(a) <= 0.1)) {
    s = std::sin(a);
    c = std::cos(a);
    return;
  }
  const double a2 = a * a;
  s = a * (1.0 - a2 * (1.0 / 6) * (1.0 - a2 * (1.0 / 20) * (1.0 - a2 * (1.0 / 42) * (1.0 - a2 * (1.0 / 72)))));
  c = 1.0 - a2 * 0.5 * (1.0 - a2 * (1.0 / 12) * (1.0 - a2 * (1.0 / 30) * (1.0 - a2 * (1.0 / 56) * (1.0 - a2 * (1.0 / 90)))));
}

// The robot stands on its wheels while its centre of mass is at most this far above where it
// rests, m; higher, its wheels are off the carpet (they push nothing and carry nothing).
constexpr double kGripHeight = 0.002;
// How far a wheel-body robot settles into the carpet, m: ODE lets a resting contact sink through
// the world's contact layer (contact_surface_layer: 0.5 mm by default and in every shipped world)
// before pushing back, and the omni drive's wheel contacts drift down through it within seconds
// (the robot comes to rest 0.5 mm low). This robot rests as low, so the two meet the ball alike:
// the dribbler's reach into the ball is tuned to that height (a robot 0.5 mm higher does not
// draw in a ball 2 mm off its face).
constexpr double kSettle = 0.0005;
// Largest yaw gain of the wheel servos (1 reaches the target in one step, 2 oscillates forever).
constexpr double kMaxYawGain = 1.8;
// Layout of SaveState's bytes: bump when they change. 2: no per-wheel friction (it is the
// world's, resolved once). 3: the gyro loop's heading error.
constexpr std::uint32_t kStateLayout = 3;

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
    gyro_ = ubersim::GyroRateLoop(p.GetDouble("heading_hold", 10.0));
    // The same surface as the omni drive's tyres: the world's table pair <name>|carpet, or the
    // two surfaces combined, decides the wheels' grip.
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
    const ubersim::SurfaceMaterial grip = ctx.CarpetSurface(surface);
    mu_axle_ = grip.mu;
    mu_roll_ = grip.mu2 < 0 ? grip.mu : grip.mu2;
    if (wheel_radius_ * 2 <= body.ground_clearance) {
      throw ubersim::PluginError("wheel_radius " + std::to_string(wheel_radius_) +
                                 " m leaves the wheels above the carpet (ground_clearance " +
                                 std::to_string(body.ground_clearance) + " m)");
    }

    ubersim::Body& chassis = ctx.Chassis();
    // The robot stands on the carpet at z = 0; the chassis origin (its centre of mass) is this high.
    const double chassis_z = chassis.GetPose().position.z();
    rest_height_ = chassis_z - kSettle;
    const ubersim::ParamView list = p["wheels"];
    if (list.Size() > static_cast<std::size_t>(kMaxWheels)) {
      throw ubersim::PluginError("omni_force takes at most " + std::to_string(kMaxWheels) + " wheels, this robot has " +
                                 std::to_string(list.Size()));
    }
    wheels_.resize(list.Size());
    for (std::size_t i = 0; i < wheels_.size(); ++i) {
      Wheel& w = wheels_[i];
      const double angle = list.At(i)["angle_deg"].AsDouble() * M_PI / 180.0;
      const Vec3 radial(std::cos(angle), std::sin(angle), 0.0);
      w.tangent = Vec3(-std::sin(angle), std::cos(angle), 0.0);
      w.centre = radial * distance_ + Vec3(0, 0, wheel_radius_ - chassis_z);
      w.axle_x = -w.tangent.y();
      w.axle_y = w.tangent.x();
      w.roll_lever = w.centre.x() * w.tangent.y() - w.centre.y() * w.tangent.x();
      w.axle_lever = w.centre.x() * w.axle_y - w.centre.y() * w.axle_x;
      columns_.tangent_x[i] = w.tangent.x();
      columns_.tangent_y[i] = w.tangent.y();
      columns_.axle_x[i] = w.axle_x;
      columns_.axle_y[i] = w.axle_y;
      columns_.roll_lever[i] = w.roll_lever;
      columns_.axle_lever[i] = w.axle_lever;
    }
    // The robot's velocity from its wheel speeds (odometry, as omni): the least-squares inverse of
    // the wheel speeds a velocity asks for.
    Eigen::MatrixXd m(wheels_.size(), 3);
    for (std::size_t i = 0; i < wheels_.size(); ++i) {
      m.row(static_cast<Eigen::Index>(i)) << wheels_[i].tangent.x(), wheels_[i].tangent.y(), distance_;
    }
    const Eigen::MatrixXd geometry = m / wheel_radius_;
    inverse_ = geometry.completeOrthogonalDecomposition().pseudoInverse();
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
    const ubersim::Body& chassis = ctx_->Chassis();
    const ubersim::Pose pose = chassis.GetPose();
    const ubersim::Twist twist = chassis.GetTwist();
    const Eigen::Matrix3d rotation = pose.orientation.toRotationMatrix();
    WheelSpeeds speeds(static_cast<Eigen::Index>(wheels_.size()));
    for (std::size_t i = 0; i < wheels_.size(); ++i) {
      const Frame fr = WheelFrame(pose.position, rotation, wheels_[i]);
      // The contact point's velocity: the chassis' origin is its centre of mass.
      const Vec3 at = twist.linear + twist.angular.cross(fr.contact - pose.position);
      speeds(static_cast<Eigen::Index>(i)) = at.dot(fr.rolling) / wheel_radius_;
    }
    ubersim::DriveFeedback f;
    f.wheel_speeds.assign(speeds.data(), speeds.data() + speeds.size());
    const Eigen::Vector3d v = inverse_ * speeds;  // forward, left, angular
    f.local_velocity.linear = Vec3(v.x(), v.y(), 0.0);
    f.local_velocity.angular = Vec3(0.0, 0.0, v.z());
    return f;
  }

  void Reset() override {
    watchdog_.Reset();
    servo_.Reset();
    gyro_.Reset();
  }

  // Put down moving (or at rest): the speed loop starts from the chassis' velocity.
  void Placed() override {
    servo_.Set(ubersim::LocalPlanarVelocity(ctx_->Chassis()));
    gyro_.Reset();
  }

  // The servo loop's memory.
  std::string SaveState() const override {
    ubersim::StateWriter w(kStateLayout);
    w.Watchdog(watchdog_).Setpoint(servo_.Setpoint()).Move(command_).Double(gyro_.HeadingError());
    return w.Take();
  }

  void RestoreState(std::string_view state) override {
    ubersim::StateReader r(state, kStateLayout, "omni_force drive");
    r.Watchdog(watchdog_);
    servo_.Set(r.Setpoint());
    command_ = r.Move();
    gyro_.SetHeadingError(r.Double());
    r.Finish();
  }

  // Puts a robot that stands on its wheels back level at its resting height (see the top).
  void PostStep(const ubersim::StepInfo&) override {
    ubersim::Body& chassis = ctx_->Chassis();
    const ubersim::Pose pose = chassis.GetPose();
    const Vec3& p = pose.position;
    if (!Standing(p)) return;  // in the air: falling
    ubersim::Twist twist = chassis.GetTwist();
    const ubersim::Quat& q = pose.orientation;
    // Level and still before the step, with its weight carried and pushed only in the plane, a
    // robot nothing hit is level and still after it, exactly: most steps end here.
    if (p.z() == rest_height_ && q.x() == 0.0 && q.y() == 0.0 && twist.linear.z() == 0.0 && twist.angular.x() == 0.0 &&
        twist.angular.y() == 0.0) {
      return;
    }
    // The turn about the vertical left of the orientation (its twist, dropping the tilt).
    ubersim::Quat yaw(q.w(), 0.0, 0.0, q.z());
    if (yaw.norm() < 1e-9) yaw = ubersim::Quat(0.0, 0.0, 0.0, 1.0);  // upside down: any heading
    chassis.SetPose(ubersim::Pose{Vec3(p.x(), p.y(), rest_height_), yaw.normalized()});
    twist.linear.z() = 0.0;
    twist.angular.x() = twist.angular.y() = 0.0;
    chassis.SetTwist(twist);
  }

  void PreStep(const ubersim::StepInfo& step) override {
    // The chassis as the step starts: the servo, the gyro and the wheels all read this one pose.
    ubersim::Body& chassis = ctx_->Chassis();
    const ubersim::Pose pose = chassis.GetPose();
    const ubersim::Twist twist = chassis.GetTwist();
    const Eigen::Vector2d heading = Heading(pose.orientation);
    const std::size_t n = wheels_.size();
    double surface[kMaxWheels];  // each wheel's surface speed, m/s
    const bool fresh = watchdog_.Fresh(ctx_->SimTime());
    const auto* direct = fresh ? std::get_if<ubersim::WheelSpeedCommand>(&command_) : nullptr;
    if (direct) {
      // Direct wheel speeds bypass the velocity loop, as on the real robots.
      const Eigen::Map<const WheelSpeeds> speeds(direct->wheel_speeds.data(),
                                                 static_cast<Eigen::Index>(direct->wheel_speeds.size()));
      for (std::size_t i = 0; i < n; ++i) {
        surface[i] = std::clamp(direct->wheel_speeds[i], -max_wheel_speed_, max_wheel_speed_) * wheel_radius_;
      }
      const Eigen::Vector3d v = inverse_ * speeds;
      servo_.Set({Eigen::Vector2d(v.x(), v.y()), v.z()});
      gyro_.Reset();
    } else {
      const ubersim::PlanarVelocity target =
          fresh ? servo_.ClampToLimits(ubersim::CommandedVelocity(command_, heading)) : ubersim::PlanarVelocity{};
      const ubersim::PlanarVelocity& set = servo_.Step(target, step.dt);
      // The firmware's gyro holds the heading the setpoint integrates to.
      const double spin = gyro_.Correct(set.angular, twist.angular.z(), step.dt);
      // In the frame the robot turns to within the step (ubersim::AheadOfTheTurn): driving while
      // turning, it keeps its course.
      double s, c;
      SinCosOfSmallTurn(spin * step.dt, s, c);
      const double lx = c * set.linear.x() - s * set.linear.y();
      const double ly = s * set.linear.x() + c * set.linear.y();
      double peak = 0.0;
      const WheelColumns& cols = columns_;
      for (std::size_t i = 0; i < n; ++i) {
        surface[i] = cols.tangent_x[i] * lx + cols.tangent_y[i] * ly + cols.roll_lever[i] * spin;
      }
      for (std::size_t i = 0; i < n; ++i) peak = std::max(peak, std::abs(surface[i]));
      // Keep the direction when a wheel would exceed its speed: scale all wheels together.
      const double max_surface = max_wheel_speed_ * wheel_radius_;
      if (peak > max_surface) {
        const double scale = max_surface / peak;
        for (std::size_t i = 0; i < n; ++i) surface[i] *= scale;
      }
    }
    if (Standing(pose.position)) PushWheels(chassis, heading, twist, surface, step.dt);  // in the air: no grip, no support
  }

 private:
  // Where a wheel meets the carpet and its directions there (world frame).
  struct Frame {
    Vec3 contact;   // under the wheel centre, at the carpet
    Vec3 rolling;   // unit, in the carpet plane: where a positive wheel speed drives the robot
    Vec3 axle;      // unit, in the carpet plane, across the rolling direction
  };

  // Whether the robot stands on its wheels, its centre of mass at `position` (see kGripHeight).
  bool Standing(const Vec3& position) const { return position.z() <= rest_height_ + kGripHeight; }

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

  // The heading of a chassis turned by `q` (ubersim::HeadingOf, from the quaternion's terms):
  // the forward axis in the carpet plane, unit; (1, 0) pointing straight up or down.
  static Eigen::Vector2d Heading(const ubersim::Quat& q) {
    const double x = 1.0 - 2.0 * (q.y() * q.y() + q.z() * q.z());
    const double y = 2.0 * (q.x() * q.y() + q.w() * q.z());
    const double length = std::sqrt(x * x + y * y);
    if (!(length > 0.0)) return Eigen::Vector2d(1.0, 0.0);
    return Eigen::Vector2d(x / length, y / length);
  }

  // Each wheel's motor and rollers push the chassis at the wheel's contact point, and the wheels
  // together carry the robot's weight. The robot stands level (PostStep), so this is planar: the
  // pushes' tilting moments are the carpet's to take, as the weight is. The force that would
  // reach the wheel's surface speed in this step if it moved its share of the robot is a stiff
  // proportional servo. Summed over the wheels it never overshoots in translation; in yaw the
  // shares act at wheel_distance on a chassis with less moment of inertia than they would have
  // there, so it overshoots by yaw_gain_ - 1 of the error each step (0.54 on the modern robot)
  // and settles in a few steps (see Configure). Worked in the robot frame, where the wheels'
  // directions and lever arms are constants, and turned into the carpet's once.
  void PushWheels(ubersim::Body& chassis, const Eigen::Vector2d& heading_unit, const ubersim::Twist& twist,
                  const double* surface, double dt) {
    const double hx = heading_unit.x(), hy = heading_unit.y();
    const double mass = chassis.Mass();
    const Vec3 gravity = ctx_->Gravity();
    const double n = static_cast<double>(wheels_.size());
    const double load = mass / n * gravity.norm();       // N: static, no load transfer
    const double gain = mass / n * servo_scale_ / dt;     // N per m/s: each wheel's share, in one step
    const double motor_force = max_torque_ / wheel_radius_;  // N at the contact
    const double drive_limit = std::min(motor_force, mu_roll_ * load);
    const double roller_limit = mu_axle_ * load;
    // The chassis' velocity in the robot frame: forward, left, and the turn.
    const double u = hx * twist.linear.x() + hy * twist.linear.y();
    const double v = hx * twist.linear.y() - hy * twist.linear.x();
    const double spin = twist.angular.z();
    // Each wheel's push first, wheel by wheel in arrays the compiler steps through two lanes at
    // a time; then the sums, in wheel order (the same additions in the same order as one loop).
    const WheelColumns& cols = columns_;
    const std::size_t count = std::min(wheels_.size(), static_cast<std::size_t>(kMaxWheels));
    double push_x[kMaxWheels], push_y[kMaxWheels], push_turn[kMaxWheels];
    for (std::size_t i = 0; i < count; ++i) {
      // The contact point's velocity along the rolling direction and along the axle.
      const double along = cols.tangent_x[i] * u + cols.tangent_y[i] * v + cols.roll_lever[i] * spin;
      const double across = cols.axle_x[i] * u + cols.axle_y[i] * v + cols.axle_lever[i] * spin;
      const double drive = std::clamp(gain * (surface[i] - along), -drive_limit, drive_limit);
      const double roller = std::clamp(-gain * across, -roller_limit, roller_limit);
      push_x[i] = cols.tangent_x[i] * drive + cols.axle_x[i] * roller;
      push_y[i] = cols.tangent_y[i] * drive + cols.axle_y[i] * roller;
      push_turn[i] = cols.roll_lever[i] * drive + cols.axle_lever[i] * roller;
    }
    double fx = 0.0, fy = 0.0, torque = 0.0;  // robot frame
    for (std::size_t i = 0; i < count; ++i) {
      fx += push_x[i];
      fy += push_y[i];
      torque += push_turn[i];
    }
    chassis.AddForce(Vec3(hx * fx - hy * fy, hy * fx + hx * fy, 0.0) - mass * gravity);
    chassis.AddTorque(Vec3(0.0, 0.0, torque));
  }

  ubersim::RobotContext* ctx_ = nullptr;
  std::vector<Wheel> wheels_;  // sized once in Configure: the contact handlers hold indices
  WheelColumns columns_;       // the wheels' planar numbers, one array each (Configure's)
  WheelsToVelocity inverse_;   // (forward, left, angular) = inverse_ · wheel speeds
  double wheel_radius_ = 0.029;
  double distance_ = 0.08;
  double max_torque_ = 0.5;
  double max_wheel_speed_ = 150;
  double servo_scale_ = 1.0;   // of each wheel's share of the mass in its servo force (<1: wheels far out)
  double mu_roll_ = 0.8;       // wheel-carpet friction along the rolling direction (the world's)
  double mu_axle_ = 0.05;      // along the axle (the rollers)
  double rest_height_ = 0.0;   // m, the centre of mass' height standing on the carpet
  ubersim::VelocityServo servo_;       // the (forward, left, angular) setpoint the wheels follow
  ubersim::GyroRateLoop gyro_;  // heading hold on the measured turn rate
  ubersim::CommandWatchdog watchdog_{0.1};
  ubersim::MoveCommand command_;
};

}  // namespace

UBERSIM_REGISTER_DRIVE(OmniForceDrive, "omni_force", "1.0.0", ubersim_plugin::kSchema)
