// SPDX-License-Identifier: Apache-2.0
// roller: a dribbler bar across the robot's flat front.
//
// The bar is a cylinder body along the robot's lateral axis on a motorised hinge to the chassis,
// placed so that it touches a ball resting against the flat face on the ball's upper near side.
// Spinning (positive speed), its surface drags that side of the ball down and back: the ball
// spins backwards, its contact with the carpet pushes it against the robot, and the bar presses
// it into the carpet. The ball is held by contact friction alone, as on a real robot, so it can
// be lost: when the robot turns or brakes harder than that friction can follow, it rolls off.
//
// With `bar_model: surface` the bar is no body: its geometries are fixed to the chassis and only
// their surface moves, at the commanded speed, in every ball contact (ODE's contact motion).
// The ball meets the same shape, coating and friction; what goes is the bar's inertia and the
// motor's torque limit (friction caps the drag at mu·N, about 0.01 N·m on the bar's radius, below
// the motor's 0.02). One body and one hinge less per robot, and the solver needs fewer
// iterations: the hinge between a 20 g bar and a 2.5 kg chassis is the stiffest joint a robot has.
#include <algorithm>
#include <cmath>
#include <string>

#include <ubersim/ubersim.hpp>

#include "ubersim_plugin_schema.hpp"

namespace {

using ubersim::Vec3;

// Layout of SaveState's bytes: bump when they change.
constexpr std::uint32_t kStateLayout = 1;

class RollerDribbler final : public ubersim::Dribbler {
 public:
  void Configure(ubersim::RobotContext& ctx) override {
    const ubersim::ParamView& p = ctx.Params();
    max_speed_ = p.GetDouble("max_speed", max_speed_);
    max_torque_ = p.GetDouble("max_torque", max_torque_);
    idle_torque_ = p.GetDouble("idle_torque", idle_torque_);
    const double radius = p.GetDouble("bar_radius", 0.0055);
    const double length = p.GetDouble("bar_length", 0.06);
    const double mass = p.GetDouble("bar_mass", 0.02);
    const double height = p.GetDouble("height", 0.038);
    const double groove = p.GetDouble("groove_width", 0.02);
    const double groove_depth = p.GetDouble("groove_depth", 0.003);
    surface_.name = "dribbler_ball";
    surface_.mu = 1.5;      // ER-Force's dribbler: friction 1.5, restitution 0.2 (physics.md §2c)
    surface_.bounce = 0.2;
    surface_.bounce_velocity = 0.1;
    if (p.Has("surface")) {
      const ubersim::ParamView s = p["surface"];
      surface_.mu = s.GetDouble("mu", surface_.mu);
      surface_.bounce = s.GetDouble("bounce", surface_.bounce);
      surface_.bounce_velocity = s.GetDouble("bounce_velocity", surface_.bounce_velocity);
    }
    preload_ = p.GetDouble("preload", preload_);
    const std::string bar_model = p.GetString("bar_model", "hinge");
    if (bar_model != "hinge" && bar_model != "surface") {
      throw ubersim::PluginError("bar_model '" + bar_model + "' is neither 'hinge' nor 'surface'");
    }
    surface_only_ = bar_model == "surface";
    if (p.Has("coating")) {
      stiffness_ = p["coating"].GetDouble("stiffness", stiffness_);
      damping_ = p["coating"].GetDouble("damping", damping_);
    }

    // Where the bar touches a ball that rests on the carpet against the flat face.
    const ubersim::RobotBodyInfo& body = ctx.BodyInfo();
    const double ball = ctx.BallRadius();
    // A centred ball touches the groove's two rims (or, without a groove, the bar's surface).
    const double half_groove = 0.5 * groove;
    if (half_groove >= ball || (groove > 0 && groove_depth >= radius) || groove >= length) {
      throw ubersim::PluginError("dribbler groove (" + std::to_string(groove) + " m wide, " +
                                 std::to_string(groove_depth) + " m deep) must be narrower than the ball and "
                                 "the bar, and shallower than the bar's radius");
    }
    const double rise = height - ball;   // bar axis above the ball's centre
    const double reach = radius + std::sqrt(ball * ball - half_groove * half_groove);  // axis to ball centre
    if (rise <= 0.0 || rise >= reach) {
      throw ubersim::PluginError("dribbler height " + std::to_string(height) +
                                 " m must be above the ball's centre (" + std::to_string(ball) +
                                 " m) and below its top plus the bar radius (" +
                                 std::to_string(ball + reach) + " m)");
    }
    // The bar sits `preload` into a ball resting at the face: its rubber coating presses the ball
    // down and back with about stiffness·preload, so a millimetre of chassis pitch or bounce does
    // not lift it off the ball.
    const double bar_x = body.front_distance + ball - std::sqrt(reach * reach - rise * rise) + preload_;

    ubersim::Body& chassis = ctx.Chassis();
    const ubersim::Pose chassis_pose = chassis.GetPose();
    const double chassis_z = chassis_pose.position.z();  // the robot stands on the carpet at z = 0
    // The cylinder's z axis along the robot's y axis: a positive hinge rate then turns the bar's
    // ball side down and back.
    const ubersim::Pose bar_local{Vec3(bar_x, 0.0, height - chassis_z),
                                  ubersim::Quat::FromTwoVectors(Vec3::UnitZ(), Vec3::UnitY())};
    ubersim::SceneNode& node = ctx.Node().AddChild("dribbler");
    ubersim::Body* bar = &chassis;
    if (!surface_only_) {
      ubersim::BodySpec bs;
      bs.name = "bar";
      bs.mass = ubersim::MassSpec::Solid(ubersim::Shape::Cylinder(radius, length), mass);
      bs.pose = chassis_pose.Compose(bar_local);
      bs.twist = chassis.GetTwist();
      bar = &node.AddBody(bs);
    }
    // The bar's geometries sit in the bar's frame: the bar body's, or the chassis' at bar_local.
    const ubersim::Pose bar_frame = surface_only_ ? bar_local : ubersim::Pose{};
    chassis_ = &chassis;
    bar_axis_local_ = bar_local.orientation * Vec3::UnitZ();
    bar_centre_local_ = bar_local.position;
    // The bar's surface: one cylinder, or a core in the groove with a rim cylinder either side.
    auto add_geom = [&](const std::string& name, double r, double l, double y) {
      ubersim::GeomSpec gs;
      gs.name = name;
      gs.shape = ubersim::Shape::Cylinder(r, l);
      gs.offset = bar_frame.Compose(ubersim::Pose{Vec3(0.0, 0.0, y), ubersim::Quat::Identity()});  // along the axis
      gs.material.name = "dribbler";
      // The surface bar grips along its axle with mu and across it, where it turns, with mu
      // while driven; switched off it turns freely with the ball (bearing friction neglected).
      if (surface_only_) gs.friction_axis = bar_axis_local_;  // chassis frame
      ubersim::Geom& geom = node.AddGeom(gs, bar);
      ctx.ObserveContacts(geom, [this](const ubersim::Contact& c, ubersim::SurfaceMaterial& s, bool&) {
        if (!c.other_is_ball) return;
        s = surface_;
        // The coating as a spring and damper (ODE's ERP/CFM for this step length).
        s.soft_erp = dt_ * stiffness_ / (dt_ * stiffness_ + damping_);
        s.soft_cfm = 1.0 / (dt_ * stiffness_ + damping_);
        if (surface_only_) {
          s.surface_velocity = SurfaceVelocity(c.position);
          s.mu2 = speed_ != 0.0 ? s.mu : 0.0;
        }
        touched_ = true;
      });
    };
    if (groove > 0.0) {
      const double rim = 0.5 * (length - groove);
      add_geom("core", radius - groove_depth, groove, 0.0);
      add_geom("rim_left", radius, rim, 0.5 * (groove + rim));
      add_geom("rim_right", radius, rim, -0.5 * (groove + rim));
    } else {
      add_geom("bar", radius, length, 0.0);
    }
    if (surface_only_) return;
    ubersim::JointSpec js;
    js.name = "axle";
    js.kind = ubersim::JointKind::kHinge;
    js.parent = &chassis;
    js.child = bar;
    const ubersim::Pose bar_pose = chassis_pose.Compose(bar_local);
    js.anchor = bar_pose.position;
    js.axis = bar_pose.orientation * Vec3::UnitZ();
    hinge_ = &node.AddJoint(js);
    hinge_->SetMotor(0.0, idle_torque_);
  }

  void SetSpeed(double rad_per_s) override {
    if (!std::isfinite(rad_per_s)) throw ubersim::PluginError("dribbler speed must be finite");
    speed_ = std::clamp(rad_per_s, -max_speed_, max_speed_);
  }

  bool TouchesBall() const override { return touched_; }

  void Reset() override {
    speed_ = 0.0;
    touched_ = false;
  }

  // The commanded speed, the last step's ball contact (read before the next step's contacts) and
  // the step length the coating's contacts use.
  std::string SaveState() const override {
    return ubersim::StateWriter(kStateLayout).Double(speed_).Bool(touched_).Double(dt_).Take();
  }

  void RestoreState(std::string_view state) override {
    ubersim::StateReader r(state, kStateLayout, "roller dribbler");
    speed_ = r.Double();
    touched_ = r.Bool();
    dt_ = r.Double();
    r.Finish();
  }

  void PreStep(const ubersim::StepInfo& step) override {
    dt_ = step.dt;
    touched_ = false;  // the coming step's contacts set it again
    // Switched off (speed 0), the motor lets the bar turn against its bearing friction only.
    if (hinge_) hinge_->SetMotor(speed_, speed_ != 0.0 ? max_torque_ : idle_torque_);
  }

 private:
  // The surface speed of a bar turning at speed_ where it touches `point` (world frame), over the
  // chassis. Switched off, the bar of surface mode stands still (it has no bearing to turn on).
  Vec3 SurfaceVelocity(const Vec3& point) const {
    const ubersim::Pose pose = chassis_->GetPose();
    const Vec3 axis = pose.orientation * bar_axis_local_;
    Vec3 radius = point - pose.Transform(bar_centre_local_);
    radius -= axis * axis.dot(radius);
    return (axis * speed_).cross(radius);
  }

  ubersim::Joint* hinge_ = nullptr;  // the bar's motorised axle (hinge model only)
  ubersim::Body* chassis_ = nullptr;
  bool surface_only_ = false;        // bar_model: surface
  Vec3 bar_axis_local_ = Vec3::UnitY();   // the bar's axis in the chassis frame
  Vec3 bar_centre_local_ = Vec3::Zero();  // a point on it, chassis frame, m
  ubersim::SurfaceMaterial surface_;
  double max_speed_ = 150.0;   // rad/s
  double max_torque_ = 0.02;   // N·m
  double idle_torque_ = 0.0005;  // N·m
  double preload_ = 0.001;     // m
  double stiffness_ = 3000.0;  // N/m, rubber coating
  double damping_ = 10.0;      // N·s/m
  double dt_ = 0.001;          // s, the step being run
  double speed_ = 0.0;         // rad/s, commanded and clamped
  bool touched_ = false;
};

}  // namespace

UBERSIM_REGISTER_DRIBBLER(RollerDribbler, "roller", "1.0.0", ubersim_plugin::kSchema)
