// SPDX-License-Identifier: Apache-2.0
// The named physics profiles a world's `physics:` block (or --profile) chooses, and keys set one by
// one over them. Every number a profile sets is validated: docs/validation (precise) and
// docs/performance.md (fast) give the runs.
#include <cstdio>
#include <sstream>
#include <stdexcept>

#include "ubersim/kernel/model.hpp"

namespace ubersim::kernel {

const std::vector<std::string>& PhysicsProfileNames() {
  static const std::vector<std::string> names = {"precise", "fast"};
  return names;
}

bool PhysicsProfile(const std::string& name, PhysicsModel& physics) {
  PhysicsModel p;  // the struct's defaults are the precise profile
  if (name == "precise") {
    // 1 ms steps, 20 QuickStep iterations, 4 contacts per pair: the reference every validation
    // band was first met at.
  } else if (name == "fast") {
    // 5 ms steps: a 6.5 m/s ball moves 33 mm a step, still under its own 43 mm diameter, and the
    // kernel's swept ball test catches what a step would carry through a wall. The islands
    // without the ball (robots driving, robots pushing one another) converge in fewer sweeps
    // than the ball's (docs/performance.md).
    p.step = 0.005;
    p.solver_iterations = 10;
    p.solver_iterations_without_ball = 2;
    p.max_contacts = 1;
    // Robots closing at 6 m/s travel 30 mm in a 5 ms step before their contact exists: they
    // meet at their surfaces instead (at 1 ms the step closes 6 mm, which a contact absorbs).
    p.speculative_robot_contacts = true;
    // ERP is the share of a contact's depth removed per step: the same 0.2 at 5 ms makes the
    // robots' shells five times softer than at 1 ms, and robots pushing each other sank 15-17 mm
    // in. 0.8 keeps them about as stiff as at the precise profile; the world's ERP (the wheels'
    // hinges, the ball's contacts) stays, as its validation bands were met there.
    p.robot_contact_erp = 0.8;
  } else {
    return false;
  }
  p.profile = name;
  physics = p;
  return true;
}

std::vector<std::string> PhysicsOverrides::Keys() const {
  std::vector<std::string> out;
  const auto add = [&out](bool set, const char* key) {
    if (set) out.emplace_back(key);
  };
  add(step.has_value(), "step");
  add(solver_iterations.has_value(), "solver_iterations");
  add(solver_iterations_without_ball.has_value(), "solver_iterations_without_ball");
  add(erp.has_value(), "erp");
  add(cfm.has_value(), "cfm");
  add(gravity.has_value(), "gravity");
  add(broadphase.has_value(), "broadphase");
  add(max_contacts.has_value(), "max_contacts");
  add(contact_surface_layer.has_value(), "contact_surface_layer");
  add(contact_max_correcting_velocity.has_value(), "contact_max_correcting_velocity");
  add(speculative_robot_contacts.has_value(), "speculative_robot_contacts");
  add(robot_contact_erp.has_value(), "robot_contact_erp");
  return out;
}

void PhysicsOverrides::ApplyTo(PhysicsModel& physics) const {
  if (profile) {
    const PhysicsOverrides world = physics.world_keys;
    if (!PhysicsProfile(*profile, physics)) {
      std::string names;
      for (const std::string& n : PhysicsProfileNames()) names += (names.empty() ? "" : ", ") + n;
      throw std::invalid_argument("no physics profile '" + *profile + "' (there are: " + names + ")");
    }
    PhysicsOverrides keys = world;
    keys.profile.reset();
    keys.ApplyTo(physics);
    physics.world_keys = world;
  }
  if (step) physics.step = *step;
  if (solver_iterations) physics.solver_iterations = *solver_iterations;
  if (solver_iterations_without_ball) physics.solver_iterations_without_ball = *solver_iterations_without_ball;
  if (erp) physics.erp = *erp;
  if (cfm) physics.cfm = *cfm;
  if (gravity) physics.gravity = *gravity;
  if (broadphase) physics.broadphase = *broadphase;
  if (max_contacts) physics.max_contacts = *max_contacts;
  if (contact_surface_layer) physics.contact_surface_layer = *contact_surface_layer;
  if (contact_max_correcting_velocity) physics.contact_max_correcting_velocity = *contact_max_correcting_velocity;
  if (speculative_robot_contacts) physics.speculative_robot_contacts = *speculative_robot_contacts;
  if (robot_contact_erp) physics.robot_contact_erp = *robot_contact_erp;
}

std::string DescribePhysics(const PhysicsModel& p) {
  std::ostringstream s;
  s << "profile " << p.profile << ": step " << p.step * 1e3 << " ms, " << p.solver_iterations << " solver iterations";
  if (p.IterationsWithoutBall() != p.solver_iterations) s << " (" << p.IterationsWithoutBall() << " without the ball)";
  s << ", " << p.max_contacts << (p.max_contacts == 1 ? " contact" : " contacts") << " per pair";
  const std::vector<std::string> keys = p.world_keys.Keys();
  if (!keys.empty()) {
    s << "; the world sets ";
    for (std::size_t i = 0; i < keys.size(); ++i) s << (i ? ", " : "") << keys[i];
  }
  return s.str();
}

}  // namespace ubersim::kernel
