// SPDX-License-Identifier: Apache-2.0
// The world: one simulated SSL field with its ball, robots, plugins and transports. It steps,
// takes events, resets, saves and restores its state, hands out the ground truth and a state hash,
// keeps the simulated clock, records plugin faults and passes camera frames to an observer.
//
// Threading contract: a World is driven from one thread (Step, ProcessEvents, Reset, Save,
// Restore, GroundTruth and the accessors); only events() may be posted to from other threads.
// ODE keeps one process-wide random generator that every step reseeds and draws from, so two
// worlds must not step at the same time in two threads of one process: run worlds in parallel in
// separate processes (as `ubersim batch` does), or step them one after another in one thread.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "ubersim/log.hpp"
#include "ubersim/world_state.hpp"
#include "ubersim/kernel/clock.hpp"
#include "ubersim/kernel/event_queue.hpp"
#include "ubersim/kernel/fault.hpp"
#include "ubersim/kernel/model.hpp"
#include "ubersim/kernel/plugin_registry.hpp"

namespace ubersim::kernel {

class WorldImpl;
class WorldAttorney;
struct SavedState;

/// Where a step's wall time went, accumulated since the start, ns.
struct StepTimings {
  std::int64_t events_ns = 0;      ///< applying events
  std::int64_t plugins_ns = 0;     ///< component PreStep/PostStep
  std::int64_t collision_ns = 0;   ///< broadphase + narrow phase + contact joints
  std::int64_t physics_ns = 0;     ///< dWorldQuickStep
  std::int64_t transports_ns = 0;  ///< Poll + Publish
  std::int64_t perception_ns = 0;  ///< camera frames: sampling, noise, latency queue
};

/// Counters of events the world applied or refused (with a log line each).
struct EventCounters {
  std::int64_t applied = 0;   ///< events applied
  std::int64_t rejected = 0;  ///< unknown robot, non-finite values, …
  std::int64_t lost = 0;      ///< robot commands the simulated radio lost
  /// Robot commands that arrived per team ([0] blue, [1] yellow), refused ones included: whether a
  /// team's software is still sending (ubersim match watches it).
  std::int64_t commands_received[2] = {0, 0};
};

/// One simulated world. Deterministic: the same model, seed and events give bit-identical
/// states. A plugin fault (fault.hpp) switches the plugin off and puts back what it broke; under
/// the world file's `on_plugin_fault: stop` the world then stops.
class World {
 public:
  /// Builds everything the model describes, loading plugins through `registry` (which must
  /// outlive the world). Throws PluginLoadError or std::runtime_error naming the plugin, robot
  /// and reason. `start_transports` false builds a world without network (tests, batch).
  World(const WorldModel& model, PluginRegistry& registry, Log& log, bool start_transports = true);
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  /// One physics step: apply queued events, components' PreStep, collide, ODE step, PostStep,
  /// answer queries, publish to transports. Does nothing once the world has stopped.
  void Step();
  /// Applies queued events and answers queries without stepping (while paused).
  void ProcessEvents();
  /// Puts everything back where the world file has it; the clock restarts at 0.
  void Reset();
  /// Reset with another seed for every random process (noise, radio loss, ODE's generator): a
  /// new episode of the same world, as a world file with that seed would give it.
  void Reset(std::uint64_t seed);

  /// The world's full state now (a step boundary), for a snapshot file (snapshot.hpp). Throws
  /// PluginError naming the part whose SaveState throws.
  SavedState Save() const;
  /// Rebuilds the world and puts `state` into it: stepping on gives what the saved world would
  /// have given, bit for bit. Throws SnapshotError when the state is of another world (another
  /// name, other bodies, robots, parts or physics) or a part refuses its saved state; the world
  /// is then as freshly built. A world restored after a fault stop steps again.
  void Restore(const SavedState& state);

  /// True once a plugin fault under `on_plugin_fault: stop` stopped the world (the step it
  /// happened in was finished without the plugin); Step does nothing from then on.
  bool stopped() const;
  /// Every plugin fault so far, oldest first.
  const std::vector<PluginFault>& faults() const;
  /// The world file's fault policy.
  FaultPolicy fault_policy() const;

  /// Where to post events (thread-safe: the one member other threads may use).
  EventQueue& events();
  /// Pause, speed, single-step and reset requests from clock events.
  ClockControl& clock_control();
  /// Simulated time and step count.
  const SimClock& clock() const;
  /// Ground truth now: every robot and the ball as they are (what transports are handed).
  WorldSnapshot GroundTruth() const;
  /// Where everything is: GroundTruth without what the robots' parts report (no drive feedback,
  /// dribbler contact or kicker readiness), a fraction of its cost. What cameras and a play that
  /// only steers need.
  WorldSnapshot Kinematics() const;
  /// A hash of every body's position, orientation and velocities, bit for bit.
  std::uint64_t StateHash() const;

  /// The model the world was built from (its field: the one in use).
  const WorldModel& model() const;
  /// Number of robots in the world.
  std::size_t robot_count() const;
  /// Accumulated time split.
  const StepTimings& timings() const;
  /// Event counters.
  const EventCounters& event_counters() const;
  /// "plugin: endpoint" of every running transport.
  std::vector<std::string> TransportEndpoints() const;
  /// Also hands every camera frame that leaves the perception pipeline to `observer` (tests,
  /// in-process users), on the simulation thread.
  void SetVisionObserver(std::function<void(const VisionFrame&)> observer);
  /// The vision system being simulated.
  const PerceptionModel& perception() const;

 private:
  friend class WorldAttorney;  // the door for the kernel's own tests and the bench (kernel/src/world)
  std::unique_ptr<WorldImpl> impl_;
};

/// The physics engine's version and build configuration (ODE's dGetConfiguration), for reports.
std::string PhysicsEngineConfiguration();

}  // namespace ubersim::kernel
