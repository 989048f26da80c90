// SPDX-License-Identifier: Apache-2.0
// solenoid: a kicker with a flat kick along the heading and a chip at the hardware's fixed angle.
//
// Real SSL kickers fire on a light barrier: the AI sends a kick speed in every radio frame, and
// the robot kicks as soon as the ball breaks the barrier. So a kick command arms the kicker for
// `arm_time` (refreshed by every new command, cleared by speed 0), and the kicker fires in the
// first step in which it is armed, charged and the ball lies in front of the flat face. A kick
// sets the ball's velocity (the robot's velocity at the ball plus the kick along its direction),
// clears the ball's spin, as a plunger blow does, and gives the robot the opposite impulse. Then
// the capacitors recharge for `recharge_time`.
#include <algorithm>
#include <cmath>
#include <string>

#include <ubersim/ubersim.hpp>

#include "ubersim_plugin_schema.hpp"

namespace {

using ubersim::Vec3;

// Layout of SaveState's bytes: bump when they change.
constexpr std::uint32_t kStateLayout = 1;

class SolenoidKicker final : public ubersim::Kicker {
 public:
  void Configure(ubersim::RobotContext& ctx) override {
    ctx_ = &ctx;
    const ubersim::ParamView& p = ctx.Params();
    max_flat_speed_ = p.GetDouble("max_flat_speed", max_flat_speed_);
    max_chip_speed_ = p.GetDouble("max_chip_speed", max_chip_speed_);
    chip_angle_ = p.GetDouble("chip_angle_deg", 45.0) * M_PI / 180.0;
    recharge_time_ = p.GetDouble("recharge_time", recharge_time_);
    arm_time_ = p.GetDouble("arm_time", arm_time_);
    half_width_ = 0.5 * p.GetDouble("width", 2 * half_width_);
    reach_ = p.GetDouble("reach", reach_);
    max_ball_height_ = p.GetDouble("max_ball_height", max_ball_height_);
    front_ = ctx.BodyInfo().front_distance;
  }

  void Reset() override {
    armed_ = false;
    charged_at_ = 0.0;
  }

  bool Kick(const ubersim::KickCommand& command) override {
    if (!std::isfinite(command.speed) || !std::isfinite(command.angle)) {
      throw ubersim::PluginError("kick speed and angle must be finite");
    }
    if (command.speed <= 0.0) {  // the AI stopped asking for a kick
      armed_ = false;
      return false;
    }
    armed_ = true;
    chip_ = command.angle > 0.0;
    speed_ = std::min(command.speed, chip_ ? max_chip_speed_ : max_flat_speed_);
    armed_until_ = ctx_->SimTime() + arm_time_;
    return TryFire();
  }

  bool Ready() const override { return ctx_->SimTime() >= charged_at_; }

  void PreStep(const ubersim::StepInfo&) override {
    if (armed_ && ctx_->SimTime() > armed_until_) armed_ = false;
    TryFire();
  }

  // Arming and charge: doubles bit for bit (printed numbers would depend on the locale).
  std::string SaveState() const override {
    return ubersim::StateWriter(kStateLayout)
        .Bool(armed_)
        .Bool(chip_)
        .Double(speed_)
        .Double(armed_until_)
        .Double(charged_at_)
        .Take();
  }

  void RestoreState(std::string_view state) override {
    ubersim::StateReader r(state, kStateLayout, "solenoid kicker");
    armed_ = r.Bool();
    chip_ = r.Bool();
    speed_ = r.Double();
    armed_until_ = r.Double();
    charged_at_ = r.Double();
    r.Finish();
  }

 private:
  // The ball's centre in the robot's horizontal frame (x forward, y left; z above the carpet).
  Vec3 BallInRobotFrame(const ubersim::Body& ball) const {
    const ubersim::Pose chassis = ctx_->Chassis().GetPose();
    const Vec3 at = ball.GetPose().position;
    // The heading's unit vector, not cos and sin of its angle: an armed kicker asks every step.
    const Eigen::Vector2d forward = ubersim::ToRobotFrame(ubersim::HeadingOf(chassis.orientation),
                                                          at.x() - chassis.position.x(), at.y() - chassis.position.y());
    return Vec3(forward.x(), forward.y(), at.z());
  }

  bool BallInZone(const ubersim::Body& ball) const {
    const Vec3 b = BallInRobotFrame(ball);
    return b.x() >= front_ && b.x() <= front_ + ctx_->BallRadius() + reach_ &&
           std::abs(b.y()) <= half_width_ && b.z() <= max_ball_height_;
  }

  bool TryFire() {
    if (!armed_) return false;  // most steps: nothing to ask the world
    ubersim::Body* ball = ctx_->Ball();
    if (!ball || !Ready() || !BallInZone(*ball)) return false;
    ubersim::Body& chassis = ctx_->Chassis();
    const double yaw = chassis.GetPose().Yaw();
    const double elevation = chip_ ? chip_angle_ : 0.0;
    const Vec3 direction(std::cos(elevation) * std::cos(yaw), std::cos(elevation) * std::sin(yaw),
                         std::sin(elevation));
    const Vec3 ball_position = ball->GetPose().position;
    // The plunger moves with the robot: the kick adds to the robot's velocity at the ball.
    const Vec3 velocity = chassis.PointVelocity(ball_position) + speed_ * direction;
    const Vec3 impulse = ball->Mass() * (velocity - ball->GetTwist().linear);
    ball->SetTwist(ubersim::Twist{velocity, Vec3::Zero()});
    ball->Wake();
    chassis.ApplyImpulse(-impulse);  // recoil
    armed_ = false;
    charged_at_ = ctx_->SimTime() + recharge_time_;
    return true;
  }

  ubersim::RobotContext* ctx_ = nullptr;
  double max_flat_speed_ = 6.5;   // m/s, the rules' limit
  double max_chip_speed_ = 5.5;   // m/s
  double chip_angle_ = M_PI / 4;  // rad
  double recharge_time_ = 0.5;    // s
  double arm_time_ = 0.1;         // s
  double half_width_ = 0.03;      // m
  double reach_ = 0.01;           // m
  double max_ball_height_ = 0.04; // m
  double front_ = 0.07;           // m, centre to the flat face
  bool armed_ = false;
  bool chip_ = false;
  double speed_ = 0.0;            // m/s, already clamped
  double armed_until_ = 0.0;      // s, sim time
  double charged_at_ = 0.0;       // s, sim time when charged again
};

}  // namespace

UBERSIM_REGISTER_KICKER(SolenoidKicker, "solenoid", "1.0.0", ubersim_plugin::kSchema)
