// SPDX-License-Identifier: Apache-2.0
// The bare-ODE baseline of `ubersim bench`: the same bodies, geometries and joints as a kernel
// world, copied handle by handle into a second ODE world that is stepped with nothing but ODE
// (a hash space, dCollide, contact joints, QuickStep). What the kernel costs on top of ODE is the
// difference between the two.
#pragma once

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "physics/island_stepper.hpp"
#include "physics/ode_handles.hpp"
#include "ubersim/kernel/world.hpp"

namespace ubersim::kernel::bench {

/// A kernel world's ODE model, rebuilt and stepped with ODE alone.
class BareOdeMirror {
 public:
  /// Copies `world` as it is now (bodies, their state, geometries, joints, solver settings).
  /// Contacts a plugin filters out (a wheel's tyre never touches the carpet, its carpet sphere
  /// touches nothing else) are filtered here with ODE's category bits, found by asking each
  /// geometry's contact observers once. Throws std::runtime_error for an ODE class it cannot copy.
  BareOdeMirror(World& world, std::uint64_t seed);  // seed: ODE's own random generator
  ~BareOdeMirror();
  BareOdeMirror(const BareOdeMirror&) = delete;
  BareOdeMirror& operator=(const BareOdeMirror&) = delete;

  /// Records what the kernel's step just set, for the baseline's next step to follow: every
  /// motor's speed and torque (the kernel's drive plugins set them), every body no joint holds
  /// where its twin in the kernel is, at its velocity (a one-body robot, whose drive plugin
  /// pushes and holds it with forces the copy does not have), and the ball when the random play
  /// moved it. Recorded, not copied at once: the kernel and the baseline then each run a stretch
  /// of steps alone, neither evicting the other's data from the processor's caches every step
  /// (measured together, each step of one ran on the other's leftovers, which cost the kernel
  /// 15 % of its speed).
  void Record(bool ball_moved);
  /// Steps recorded so far and not yet stepped.
  std::size_t recorded() const { return recorded_; }
  /// Steps once per recorded step (collide, QuickStep, clear contacts), each following what was
  /// recorded for it; forgets them. Returns the time the steps took (the following not counted).
  std::chrono::steady_clock::duration StepRecorded();

  /// Bodies, geometries, joints copied.
  int bodies() const { return static_cast<int>(bodies_.size()); }
  int geoms() const { return static_cast<int>(geoms_.size()); }   ///< geometries copied
  int joints() const { return static_cast<int>(joints_.size()); } ///< joints copied
  /// Position of the index-th body, in the kernel scene's body order (ForEachBody).
  Vec3 BodyPosition(int index) const {
    const dReal* p = dBodyGetPosition(bodies_.at(static_cast<std::size_t>(index)).get());
    return Vec3(p[0], p[1], p[2]);
  }
  /// Contact joints made in the last step.
  int last_contacts() const { return last_contacts_; }

 private:
  struct Motor {
    dJointID kernel;  // the joint in the kernel world
    dJointID copy;    // its copy here
  };
  struct Twin {
    dBodyID kernel;  // a body in the kernel world
    dBodyID copy;    // its copy here
  };
  // One body's state as Record keeps it: position, quaternion, linear and angular velocity.
  using BodyState = std::array<dReal, 13>;
  static BodyState Read(dBodyID b);
  static void Write(dBodyID b, const BodyState& s);
  static void NearCallback(void* data, dGeomID a, dGeomID b);
  void Collide(dGeomID a, dGeomID b);
  void Step();

  OdeLibrary ode_;
  OdeWorld world_;
  OdeSpace space_;
  OdeJointGroup contacts_;
  std::vector<OdeBody> bodies_;
  std::vector<OdeGeom> geoms_;
  std::vector<OdeJoint> joints_;
  std::vector<Motor> motors_;
  std::vector<Twin> free_;                // bodies no joint holds, the ball excepted
  // Recorded steps, one after the other: each step's motors (speed, torque), free bodies and
  // whether the ball moved, then the ball's state where it did.
  std::size_t recorded_ = 0;
  std::vector<dReal> motor_log_;
  std::vector<BodyState> body_log_;
  std::vector<char> ball_moved_log_;
  IslandStepper islands_;                 // the kernel's iterations per island, in plain ODE calls
  std::vector<dBodyID> body_ids_, ball_ids_;  // bodies newest first
  std::vector<IterationDemand> demands_;      // robots whose model asks for more iterations
  std::vector<char> limbs_;                   // per body of body_ids_: FindLimbs
  dBodyID ball_ = nullptr;
  dBodyID kernel_ball_ = nullptr;
  double step_ = 0.001;
  int max_contacts_ = 4;
  int last_contacts_ = 0;
  unsigned long ode_seed_ = 0;
};

/// What the kernel's own collision pass made in `world`'s last step, the kernel's side of
/// BareOdeMirror::last_contacts() (bench's contacts per step against the robots). Here, beside
/// the mirror, because only the mirror's files may reach into the kernel's internals.
struct KernelCollisionCounts {
  std::size_t contacts = 0;        ///< contact joints made
  std::size_t touching_pairs = 0;  ///< geometry pairs with at least one contact
  std::size_t narrow_tests = 0;    ///< pairs the narrow phase tested
};
KernelCollisionCounts LastCollisionCounts(World& world);

}  // namespace ubersim::kernel::bench
