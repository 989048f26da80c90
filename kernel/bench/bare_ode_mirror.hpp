// SPDX-License-Identifier: Apache-2.0
// The bare-ODE baseline of `ubersim bench`: the same bodies, geometries and joints as a kernel
// world, copied handle by handle into a second ODE world that is stepped with nothing but ODE
// (a hash space, dCollide, contact joints, QuickStep). What the kernel costs on top of ODE is the
// difference between the two.
#pragma once

#include <cstdint>
#include <random>
#include <vector>

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
  BareOdeMirror(World& world, std::uint64_t seed);
  ~BareOdeMirror();
  BareOdeMirror(const BareOdeMirror&) = delete;
  BareOdeMirror& operator=(const BareOdeMirror&) = delete;

  /// One step: motors get new seeded random speeds every 0.5 s and the ball a random kick
  /// every 1.5 s (as the kernel world's random play), then collide, QuickStep, clear contacts.
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
    dJointID joint;
    double max_speed;  // rad/s (or m/s), the range of the random commands
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
  dBodyID ball_ = nullptr;
  double step_ = 0.001;
  int max_contacts_ = 4;
  std::int64_t steps_ = 0;
  int last_contacts_ = 0;
  unsigned long ode_seed_ = 0;
  std::mt19937_64 rng_;
};

}  // namespace ubersim::kernel::bench
