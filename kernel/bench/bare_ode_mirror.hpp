// SPDX-License-Identifier: Apache-2.0
// The bare-ODE baseline of `ubersim bench`: the same bodies, geometries and joints as a kernel
// world, copied handle by handle into a second ODE world that is stepped with nothing but ODE
// (a hash space, dCollide, contact joints, QuickStep). What the kernel costs on top of ODE is the
// difference between the two.
#pragma once

#include <cstdint>
#include <vector>

#include "ubersim/kernel/island_stepper.hpp"
#include "ubersim/kernel/ode_handles.hpp"
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

  /// Gives every motor the speed and torque its twin in `world` has now (the kernel's drive
  /// plugins set them), so both worlds drive the same way; not part of the timed step.
  void FollowMotors();
  /// Puts the ball where the kernel's is, at its velocity (after the random play moved it).
  void FollowBall();
  /// One step: collide, QuickStep, clear contacts.
  void Step();

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
  static void NearCallback(void* data, dGeomID a, dGeomID b);
  void Collide(dGeomID a, dGeomID b);

  OdeLibrary ode_;
  OdeWorld world_;
  OdeSpace space_;
  OdeJointGroup contacts_;
  std::vector<OdeBody> bodies_;
  std::vector<OdeGeom> geoms_;
  std::vector<OdeJoint> joints_;
  std::vector<Motor> motors_;
  IslandStepper islands_;                 // the kernel's iterations per island, in plain ODE calls
  std::vector<dBodyID> body_ids_, ball_ids_;
  dBodyID ball_ = nullptr;
  dBodyID kernel_ball_ = nullptr;
  double step_ = 0.001;
  int max_contacts_ = 4;
  int last_contacts_ = 0;
  unsigned long ode_seed_ = 0;
};

}  // namespace ubersim::kernel::bench
