// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "ubersim/component.hpp"
#include "collision/collision.hpp"
#include "world/fault_monitor.hpp"
#include "ubersim/kernel/logging.hpp"
#include "ubersim/kernel/model.hpp"
#include "ubersim/kernel/plugin_registry.hpp"
#include "physics/scene_graph.hpp"
#include "ubersim/world_state.hpp"

namespace ubersim::kernel {

/// Services the world lends its robots.
struct RobotServices {
  BodyImpl* ball = nullptr;      ///< the ball body
  double ball_radius = 0.0215;   ///< m
  Vec3 gravity = Vec3(0, 0, -9.81);
  const std::int64_t* sim_time_ns = nullptr;  ///< the world's clock
  FaultMonitor* faults = nullptr;              ///< where plugin faults are reported
  const LastGoodState* last_good = nullptr;    ///< what bodies a fault broke are put back to
  const MaterialTable* materials = nullptr;    ///< the world's material pairs (set by the world)
  SurfaceMaterial carpet;                      ///< the carpet's surface
};

/// One part's state as a snapshot keeps it.
struct PartState {
  PluginKind kind = PluginKind::kDrive;  ///< drive, dribbler or kicker
  std::string plugin;                    ///< plugin id
  std::string version;                   ///< the plugin's version when saved
  bool failed = false;                   ///< switched off after a fault
  std::string state;                     ///< what the component's SaveState returned
};

/// A robot: its node, chassis built from the model's body block, and its drive, dribbler and
/// kicker plugins, each with its own context. Every call into a plugin is guarded: a part that
/// throws where it may not, or leaves a non-finite value behind, is reported once to the
/// world's FaultMonitor and switched off (its motors stopped, its contact handlers silenced), and
/// what it broke is put back to the last good state; the robot carries on without it.
class Robot {
 public:
  /// Builds the chassis under `team_node` and creates and configures the plugins.
  Robot(const RobotPlacement& placement, NodeImpl& team_node, PluginRegistry& registry, Log& log,
        const RobotServices& services);
  ~Robot();

  const RobotId& id() const { return id_; }         ///< team and id
  BodyImpl& chassis() { return *chassis_; }         ///< chassis body
  NodeImpl& node() { return *node_; }               ///< the robot's node
  bool present() const { return present_; }         ///< on the field
  double dribbler_speed() const { return dribbler_speed_; }  ///< the last commanded roller speed, rad/s
  /// True when its dribbler touched the ball in the last step (false without a working dribbler).
  bool TouchesBall() const;
  const RobotModel& model() const { return *model_; }  ///< what it was built from

  /// Components' PreStep (drive, dribbler, kicker order).
  void PreStep(const StepInfo& step);
  /// Components' PostStep.
  void PostStep(const StepInfo& step);
  /// Applies a command event's parts to the components it has; false with a reason if a part
  /// has no component to take it.
  bool Command(const CommandEvent& e, std::string& why);
  /// Moves the whole robot (every body of its subtree) rigidly to (x, y, yaw).
  void Teleport(double x, double y, double yaw);
  /// Sets the velocity of every body of the robot (world frame, about the chassis origin).
  void SetVelocity(const Vec3& linear, const Vec3& angular);
  /// Tells the drive the robot was put somewhere (after Teleport and SetVelocity): Drive::Placed.
  void Placed();
  /// Takes the robot off the field (no collisions, frozen) or puts it back.
  void SetPresent(bool present);
  /// Ground truth.
  RobotState State() const;
  /// Ground truth without what its parts report (no dribbler contact, kicker charge or drive
  /// feedback): where it is and how it moves, for the cameras.
  RobotState Kinematics() const;
  /// Kinematics() written into `s`, a default RobotState (a snapshot's, built in place).
  void WriteKinematics(RobotState& s) const;

  /// Reports and puts back the robot's non-finite bodies, found in `step` where no plugin call
  /// can be blamed (`when`: "after the physics step", …; `what`: the state check's finding). A
  /// robot found so in two steps running is taken off the field.
  void RepairNonFinite(const char* when, std::int64_t step, const std::string& what);
  /// Every part's state (SaveState); throws PluginError naming the part when one throws.
  std::vector<PartState> SaveParts() const;
  /// Puts back what SaveParts returned (RestoreState, parts that were switched off switched off
  /// again); throws PluginError naming the part that refuses, or when the parts differ.
  void RestoreParts(const std::vector<PartState>& parts);

 private:
  class Context;
  struct Part;
  void RunPhase(bool pre, const StepInfo& step);
  // Switches a part off after a fault and reports it (once).
  void Fail(Part& part, const std::string& phase, const std::string& what);
  // Runs `call` (a call into `part`), turning an escaping exception into a fault of `phase`,
  // then checks what it may have broken. False when the part failed.
  template <typename F>
  bool Guarded(Part& part, const char* phase, F&& call);
  // As Guarded for a query (TouchesBall, Ready), which changes nothing to check afterwards.
  template <typename F>
  void Queried(Part& part, const char* phase, F&& call) const;
  // After a call into `part` left a non-finite value in the robot or the ball: its fault.
  void ReportNonFinite(Part& part, const char* phase);
  // Puts the robot's and the ball's non-finite bodies back to the last good state.
  void Repair();
  void BuildCylinderChassis(const RobotPlacement& placement);
  void BuildUrdfBodies(const RobotPlacement& placement);

  RobotId id_;
  const RobotServices& services_;
  PrefixedLog log_;
  std::shared_ptr<const RobotModel> model_;
  NodeImpl* node_ = nullptr;
  BodyImpl* chassis_ = nullptr;
  bool present_ = true;
  double dribbler_speed_ = 0.0;
  double rest_height_ = 0.0;
  std::vector<std::unique_ptr<Part>> parts_;  // drive, dribbler, kicker (those present)
  Part* part_of_[3] = {};                     // the same by kind (kDrive first); null: none
  // The part of `kind` (drive, dribbler or kicker), or null: the robot has none.
  Part* PartOf(PluginKind kind) const {
    return kind == PluginKind::kTransport ? nullptr : part_of_[static_cast<std::size_t>(kind) - 1];
  }
  Drive* drive_ = nullptr;
  Dribbler* dribbler_ = nullptr;
  Kicker* kicker_ = nullptr;
  BodyWatch watch_;               // the robot's bodies and the ball, checked after each plugin call
  std::int64_t repaired_at_ = -2;  // the last step the kernel had to repair it in
};

}  // namespace ubersim::kernel
