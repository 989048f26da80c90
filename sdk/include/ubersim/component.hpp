// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <string_view>

#include "ubersim/events.hpp"
#include "ubersim/export.hpp"
#include "ubersim/log.hpp"
#include "ubersim/math.hpp"
#include "ubersim/params.hpp"
#include "ubersim/scene.hpp"
#include "ubersim/world_state.hpp"

namespace ubersim {
inline namespace v1 {

/// Timing of the physics step being run.
struct StepInfo {
  std::int64_t step = 0;         ///< index of this step, from 0
  double dt = 0.0;               ///< step length, s
  std::int64_t sim_time_ns = 0;  ///< simulated time at the start of the step, ns
};

/// The robot's body as its model file gives it (the kernel builds the chassis from it).
struct RobotBodyInfo {
  double mass = 0.0;               ///< chassis mass, kg (parts add their own)
  double radius = 0.09;            ///< m
  double height = 0.15;            ///< m
  double front_distance = 0.07;    ///< centre to the flat front (dribbler/kicker face), m
  double ground_clearance = 0.0;   ///< chassis bottom above the carpet, m
  /// Centre of mass above the carpet, m (the chassis body's origin); < 0: the chassis' centre.
  double center_of_mass_height = -1.0;
};

/// One contact a component asked to observe, as the collision manager finds it.
struct Contact {
  Geom* own = nullptr;          ///< the observed geometry
  Geom* other = nullptr;        ///< what it touches
  bool other_is_ball = false;   ///< `other` is the ball
  Vec3 position = Vec3::Zero(); ///< contact point, world, m
  Vec3 normal = Vec3::UnitZ();  ///< unit normal, world, pointing from `other` into `own`
  double depth = 0.0;           ///< penetration, m
};

/// Called for each contact of an observed geometry before the contact joint is made; may change
/// the surface used for this contact, or set `accept` to false to drop the contact.
using ContactHandler = std::function<void(const Contact& contact, SurfaceMaterial& surface,
                                          bool& accept)>;

/// What the kernel gives a robot component: its robot, its parameters and services.
class UBERSIM_SDK_API RobotContext {
 public:
  virtual ~RobotContext();
  /// Team and id of the robot.
  virtual RobotId Id() const = 0;
  /// The robot's scene node ("blue/3"); add parts as children or to it.
  virtual SceneNode& Node() = 0;
  /// The chassis body the kernel built from the model's `body:` block.
  virtual Body& Chassis() = 0;
  /// The `body:` block's dimensions.
  virtual const RobotBodyInfo& BodyInfo() const = 0;
  /// This component's own parameter block, already validated against its schema.
  virtual const ParamView& Params() const = 0;
  /// A log that prefixes the robot and plugin name.
  virtual Log& Logger() = 0;
  /// Simulated time now, s.
  virtual double SimTime() const = 0;
  /// The ball's body (nullptr in a world without a ball).
  virtual Body* Ball() = 0;
  /// The ball's radius, m.
  virtual double BallRadius() const = 0;
  /// Gravity, m/s², world.
  virtual Vec3 Gravity() const = 0;
  /// Calls `handler` for every contact of `own` (one of this robot's geometries) while the robot lives.
  virtual void ObserveContacts(Geom& own, ContactHandler handler) = 0;
  /// The surface a contact of `own` with the carpet gets (the world's material pair, else the
  /// two combined): for parts that compute their carpet forces themselves instead of touching it.
  virtual SurfaceMaterial CarpetSurface(const SurfaceMaterial& own) const = 0;
};

/// Base of robot parts (drive, dribbler, kicker). The kernel calls Configure once, then each step
/// PreStep (write actuators) before physics and PostStep (read results) after it.
class UBERSIM_SDK_API Component {
 public:
  virtual ~Component();
  /// Builds the part into the robot's node and reads parameters; throw PluginError on bad input.
  virtual void Configure(RobotContext& context) = 0;
  /// Returns to the state right after Configure (commands cleared).
  virtual void Reset() {}
  /// Before the physics step: set motors, forces.
  virtual void PreStep(const StepInfo& /*step*/) {}
  /// After the physics step: read sensors, update internal state.
  virtual void PostStep(const StepInfo& /*step*/) {}
  /// Internal state as bytes (for snapshots); empty when stateless.
  virtual std::string SaveState() const { return {}; }
  /// Restores what SaveState returned.
  virtual void RestoreState(std::string_view /*state*/) {}
};

/// Turns move commands into motion (omni wheels, differential, …).
class UBERSIM_SDK_API Drive : public Component {
 public:
  ~Drive() override;
  /// Sets the command the servo loop follows until the next one (or the command timeout).
  virtual void SetCommand(const MoveCommand& command) = 0;
  /// Measured wheel speeds and velocity.
  virtual DriveFeedback Feedback() const = 0;
  /// The kernel has just put the robot somewhere (a client's teleport): the chassis and every
  /// body of the robot have their new pose and the velocity the client gave (at rest if it gave
  /// none), all moving as one rigid body. A drive takes that motion as its own — its wheels
  /// rolling with it (RollWheel), its speed loop starting from it — so the robot drives on from
  /// there instead of its wheels skidding the chassis to the old setpoint at full friction.
  virtual void Placed() {}
};

/// Spins the ball back against the robot.
class UBERSIM_SDK_API Dribbler : public Component {
 public:
  ~Dribbler() override;
  /// Roller speed, rad/s (clamped to the configured maximum; 0 stops it).
  virtual void SetSpeed(double rad_per_s) = 0;
  /// True when the roller touched the ball in the last step.
  virtual bool TouchesBall() const = 0;
};

/// Kicks the ball flat or chipped.
class UBERSIM_SDK_API Kicker : public Component {
 public:
  ~Kicker() override;
  /// Kicks now if charged and the ball is in front; true when the ball was kicked.
  virtual bool Kick(const KickCommand& command) = 0;
  /// True when charged.
  virtual bool Ready() const = 0;
};

}  // namespace v1
}  // namespace ubersim
