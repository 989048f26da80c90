// SPDX-License-Identifier: Apache-2.0
// The world's insides, behind the public World (kernel/world.hpp forwards to it): what it owns,
// how a step runs. Reached from outside the kernel only through WorldAttorney.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "ubersim/events.hpp"
#include "ubersim/log.hpp"
#include "ubersim/world_state.hpp"
#include "ubersim/kernel/clock.hpp"
#include "ubersim/kernel/event_queue.hpp"
#include "ubersim/kernel/fault.hpp"
#include "ubersim/kernel/model.hpp"
#include "ubersim/kernel/plugin_registry.hpp"
#include "ubersim/kernel/world.hpp"
#include "collision/collision.hpp"
#include "perception/radio_link.hpp"
#include "perception/vision_pipeline.hpp"
#include "physics/island_stepper.hpp"
#include "physics/ode_handles.hpp"
#include "physics/scene_graph.hpp"
#include "world/fault_monitor.hpp"
#include "world/held_ball.hpp"
#include "world/repeated_warnings.hpp"

namespace ubersim::kernel {

class Robot;
class TransportHost;
struct RobotServices;
struct SavedState;

/// One simulated world: ODE world, scene graph, collision manager, field, ball, robots with
/// their plugins, transports, events and the clock. Deterministic: the same model, seed and
/// events give bit-identical states. A plugin fault (fault.hpp) switches the plugin off and puts
/// back what it broke; under the world file's `on_plugin_fault: stop` the world then stops.
class WorldImpl {
 public:
  /// Builds everything the model describes, loading plugins through `registry`. Throws
  /// PluginLoadError or std::runtime_error naming the plugin, robot and reason.
  /// `start_transports` false builds a world without network (tests, batch).
  WorldImpl(const WorldModel& model, PluginRegistry& registry, Log& log, bool start_transports = true);
  ~WorldImpl();
  WorldImpl(const WorldImpl&) = delete;
  WorldImpl& operator=(const WorldImpl&) = delete;

  /// One physics step: apply queued events, components' PreStep, collide, QuickStep, PostStep,
  /// answer queries, publish to transports. Does nothing once the world has stopped.
  void Step();
  /// Applies queued events and answers queries without stepping (while paused).
  void ProcessEvents();
  /// Puts everything back where the world file has it; the clock restarts at 0.
  void Reset();
  void Reset(std::uint64_t seed);

  /// The world's full state now (a step boundary), for a snapshot file. Throws PluginError
  /// naming the part whose SaveState throws.
  SavedState Save() const;
  /// Rebuilds the world and puts `state` into it: stepping on gives what the saved world would
  /// have given, bit for bit. Throws SnapshotError when the state is of another world (another
  /// name, other bodies, robots, parts or physics) or a part refuses its saved state; the world
  /// is then as freshly built. A world restored after a fault stop steps again.
  void Restore(const SavedState& state);

  /// True once a plugin fault under `on_plugin_fault: stop` stopped the world (the step it
  /// happened in was finished without the plugin); Step does nothing from then on.
  bool stopped() const { return stopped_; }
  /// Every plugin fault so far, oldest first.
  const std::vector<PluginFault>& faults() const { return faults_.faults(); }
  /// The world file's fault policy.
  FaultPolicy fault_policy() const { return faults_.policy(); }

  /// Where to post events (thread-safe).
  EventQueue& events() { return events_; }
  /// Pause, speed, single-step and reset requests from clock events.
  ClockControl& clock_control() { return clock_control_; }
  /// Simulated time and step count.
  const SimClock& clock() const { return clock_; }
  /// Ground truth now.
  WorldSnapshot GroundTruth() const;
  /// GroundTruth without what robots' parts report (Robot::Kinematics): what cameras see.
  WorldSnapshot Kinematics() const;
  /// Each robot's centre-to-front distance in `truth.robots`' order, when the cameras need them.
  std::vector<double> FrontDistances(const WorldSnapshot& truth) const;
  /// Holds the ball to the robot whose turning dribbler touches it, or lets it go (held_ball_).
  void UpdateHeldBall();
  /// A hash of every body's position, orientation and velocities, bit for bit.
  std::uint64_t StateHash() const;

  /// The model the world was built from.
  const WorldModel& model() const { return model_; }
  /// The scene graph.
  SceneGraph& scene() { return *scene_; }
  /// The scene graph, read-only (state checks).
  const SceneGraph& scene() const { return *scene_; }
  /// The collision manager.
  CollisionManager& collision() { return *collision_; }
  /// The ball body.
  BodyImpl& ball() { return *ball_; }
  /// Number of robots.
  std::size_t robot_count() const { return robots_.size(); }
  /// The ODE world.
  dWorldID ode_world() const { return world_.get(); }
  /// Accumulated time split.
  const StepTimings& timings() const { return timings_; }
  /// Event counters.
  const EventCounters& event_counters() const { return event_counters_; }
  /// "plugin: endpoint" of every running transport.
  std::vector<std::string> TransportEndpoints() const;
  /// Also hands every camera frame that leaves the perception pipeline to `observer` (tests,
  /// in-process users), on the simulation thread.
  void SetVisionObserver(std::function<void(const VisionFrame&)> observer) { vision_observer_ = std::move(observer); }
  /// The vision system being simulated.
  const PerceptionModel& perception() const { return perception_.model(); }

 private:
  // The ground truth, with the robots' parts asked for their reports or not.
  WorldSnapshot Snapshot(bool parts) const;
  void Build();
  // Reset without telling the transports (Reset and Restore).
  void Rebuild();
  // Bodies that went non-finite where no plugin call can be blamed (`when`: "after the physics
  // step", "before the step") are put back to the last good state and reported.
  void RepairNonFinite(const char* when);
  // A digest of what decides the trajectory besides the state: bodies, robots, physics.
  std::uint64_t StructureDigest() const;
  // Hands the transports the state as it is (at start and after a reset, without a step).
  void PublishGroundTruth();
  void ApplyEvents(bool stepping);
  void Apply(const PositionEvent& e);
  void Apply(CommandEvent&& e);  // moved on into the radio
  void Deliver(const CommandEvent& e);
  void Apply(const ClockEvent& e);
  void Apply(const RealismEvent& e);
  void Apply(const RobotSpecEvent& e);
  void Apply(const FieldEvent& e);
  void Apply(const TransportSettingEvent& e);
  ObjectState Query(const Target& t) const;
  Robot* FindRobot(const RobotId& id) const;
  // The same, looking first at the robot after `hint` (updated to follow the one found).
  Robot* FindRobot(const RobotId& id, std::size_t& hint) const;
  // Builds a robot under its team's node from its base model with its announced spec, and adds
  // it to the roster; a robot that fails to build leaves nothing behind (and throws).
  Robot& AddRobot(const RobotPlacement& placement);
  // Takes a robot out of the world: its parts, then its bodies; and out of the roster.
  void RemoveRobot(const RobotId& id);
  // After robots came or went: the collision manager, the repair records, the body list.
  void RobotsChanged();
  // A robot that is not in the world comes on (PositionEvent with present: true); null, with
  // the reasons in `answer`, when it cannot.
  Robot* ComeOn(const PositionEvent& e, EventAnswer& answer);
  // Rebuilds a robot from its (new) model where it is, as it moves; on failure as it was.
  void RebuildRobot(Robot& robot, EventAnswer& answer);
  // The model `placement`'s robot is built from: its base with the spec announced for it.
  std::shared_ptr<const RobotModel> EffectiveModel(const RobotPlacement& placement);
  // The base model of robot `id`: its roster entry's, else its team's (may be null).
  std::shared_ptr<const RobotModel> BaseModel(const RobotId& id) const;
  // The fields a client may switch to: the world's own, its `fields:`, the world file's.
  std::vector<std::shared_ptr<const FieldModel>> KnownFields() const;
  // Makes `field` the world's (geometry, cameras) without building it.
  void UseField(std::shared_ptr<const FieldModel> field);
  // Builds `field` in place of the current one, keeping robots and ball (moved inside the walls).
  void ChangeField(std::shared_ptr<const FieldModel> field);
  // Applies robot specs to models (the kernel's schemas and the registry's plugin schemas).
  const ModelLoader& Loader();

  WorldModel model_;
  PluginRegistry& registry_;
  Log& log_;
  bool start_transports_;
  OdeLibrary ode_;
  // The destructor tears down in this order: transports stop (their threads may still post
  // events), then the robots (and their plugin libraries' objects), the collision manager, the
  // scene graph, and the ODE world last.
  OdeWorld world_;
  std::unique_ptr<SceneGraph> scene_;
  HeldBall held_;  // after world_: its joint goes before the world does
  std::unique_ptr<CollisionManager> collision_;
  BodyImpl* ball_ = nullptr;
  IslandStepper islands_;
  std::vector<IterationDemand> iteration_demands_;  // robots that ask for more iterations (scratch)
  std::vector<dBodyID> body_ids_, ball_ids_;  // the step's bodies for islands_, reused
  std::vector<char> limbs_;                   // per body of body_ids_: FindLimbs
  std::uint64_t body_ids_for_ = 0;             // body_ids_ lists this many bodies created
  std::vector<std::unique_ptr<Robot>> robots_;
  // What Build builds, in creation order, each with its base model: the world file's robots,
  // then those that came on while running (a rebuilt robot goes to the end, as its bodies do).
  std::vector<RobotPlacement> roster_;
  // Robot specs announced while running, by robot: kept over a reset (they describe a team's
  // robots), saved in snapshots. spec_models_ caches their models, with the base they were made from.
  std::map<std::pair<int, int>, RobotSpec> specs_;
  std::map<std::pair<int, int>, std::pair<std::shared_ptr<const RobotModel>, std::shared_ptr<const RobotModel>>>
      spec_models_;
  std::unique_ptr<ModelLoader> loader_;
  std::vector<Event> drained_;      // this step's events (its storage goes back to the queue)
  std::size_t sent_hint_ = 0;       // FindRobot's hints for commands sent and delivered
  std::size_t delivered_hint_ = 0;
  std::uint64_t roster_version_ = 0;  // counts robots coming, going and rebuilt
  std::shared_ptr<const FieldModel> initial_field_;  // the world file's (a reset goes back to it)
  NodeImpl* team_nodes_[2] = {nullptr, nullptr};  // blue, yellow
  std::vector<std::unique_ptr<TransportHost>> transports_;
  FieldGeometry field_geometry_;
  EventQueue events_;
  std::vector<QueryEvent> pending_queries_;
  ClockControl clock_control_;
  SimClock clock_;
  unsigned long ode_random_seed_;
  std::int64_t sim_time_ns_ = 0;
  std::unique_ptr<RobotServices> robot_services_holder_;
  StepTimings timings_;
  EventCounters event_counters_;
  PerceptionPipeline perception_;
  RadioLink radio_;
  std::vector<bool> responses_lost_;  // per robot in robots_' order: its feedback lost this step
  bool held_ball_ = false;            // dribblers hold the ball by a constraint (model, realism events)
  std::int64_t hold_after_ns_ = 0;    // no hold before this time (a kick just happened)
  std::function<void(const VisionFrame&)> vision_observer_;
  FaultMonitor faults_;
  RepeatedWarnings repeated_{log_, 1'000'000'000};  // refused commands: one line per robot per simulated second
  LastGoodState last_good_;
  bool stopped_ = false;
};

}  // namespace ubersim::kernel
