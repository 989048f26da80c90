// SPDX-License-Identifier: Apache-2.0
// A surface's numbers without its name: what a contact's handlers may change, copied per contact.
#pragma once

#include "ubersim/scene.hpp"

namespace ubersim::kernel {

/// The values of a SurfaceMaterial, its name left out: copying a name is most of the cost of
/// copying a surface, and the kernel reads none once a contact's handlers have run.
struct SurfaceValues {
  double mu, mu2, bounce, bounce_velocity, soft_erp, soft_cfm, rolling_friction, slip;
  Vec3 surface_velocity;

  /// The values of `s`.
  static SurfaceValues Of(const SurfaceMaterial& s) {
    return {s.mu, s.mu2, s.bounce, s.bounce_velocity, s.soft_erp, s.soft_cfm, s.rolling_friction, s.slip,
            s.surface_velocity};
  }
  /// Writes these values into `s`, leaving its name.
  void WriteTo(SurfaceMaterial& s) const {
    s.mu = mu;
    s.mu2 = mu2;
    s.bounce = bounce;
    s.bounce_velocity = bounce_velocity;
    s.soft_erp = soft_erp;
    s.soft_cfm = soft_cfm;
    s.rolling_friction = rolling_friction;
    s.slip = slip;
    s.surface_velocity = surface_velocity;
  }
};

}  // namespace ubersim::kernel
