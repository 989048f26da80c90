// SPDX-License-Identifier: Apache-2.0
// The public World forwards to WorldImpl (world_impl.hpp), so that its header names nothing of
// ODE, the scene graph or the plugins' hosts.
#include "ubersim/kernel/world.hpp"

#include <ode/ode.h>

#include "ubersim/kernel/snapshot.hpp"
#include "world/world_impl.hpp"

namespace ubersim::kernel {

World::World(const WorldModel& model, PluginRegistry& registry, Log& log, bool start_transports)
    : impl_(std::make_unique<WorldImpl>(model, registry, log, start_transports)) {}
World::~World() = default;

void World::Step() { impl_->Step(); }
void World::ProcessEvents() { impl_->ProcessEvents(); }
void World::Reset() { impl_->Reset(); }
void World::Reset(std::uint64_t seed) { impl_->Reset(seed); }
SavedState World::Save() const { return impl_->Save(); }
void World::Restore(const SavedState& state) { impl_->Restore(state); }
bool World::stopped() const { return impl_->stopped(); }
const std::vector<PluginFault>& World::faults() const { return impl_->faults(); }
FaultPolicy World::fault_policy() const { return impl_->fault_policy(); }
EventQueue& World::events() { return impl_->events(); }
ClockControl& World::clock_control() { return impl_->clock_control(); }
const SimClock& World::clock() const { return impl_->clock(); }
WorldSnapshot World::GroundTruth() const { return impl_->GroundTruth(); }
WorldSnapshot World::Kinematics() const { return impl_->Kinematics(); }
std::uint64_t World::StateHash() const { return impl_->StateHash(); }
const WorldModel& World::model() const { return impl_->model(); }
std::size_t World::robot_count() const { return impl_->robot_count(); }
const StepTimings& World::timings() const { return impl_->timings(); }
const EventCounters& World::event_counters() const { return impl_->event_counters(); }
std::vector<std::string> World::TransportEndpoints() const { return impl_->TransportEndpoints(); }
void World::SetVisionObserver(std::function<void(const VisionFrame&)> observer) {
  impl_->SetVisionObserver(std::move(observer));
}
const PerceptionModel& World::perception() const { return impl_->perception(); }

std::string PhysicsEngineConfiguration() { return dGetConfiguration(); }

}  // namespace ubersim::kernel
