// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <ode/ode.h>

#include "ubersim/math.hpp"
#include "ubersim/scene.hpp"

namespace ubersim::kernel {

/// An SSL robot's shell: a vertical cylinder cut flat at the front (its x axis). The kernel
/// builds it as a triangle mesh (every shape collides with that); two shells that both stand
/// upright meet here instead, exactly and in about a hundredth of ODE's mesh-against-mesh time.
struct FlatFrontPrism {
  double radius = 0.09;          ///< m
  double front_distance = 0.07;  ///< centre to the flat face, m (≥ radius: no face)
  double half_height = 0.07;     ///< m, about the geometry's origin
};

/// The shell as a closed triangle mesh about its centre (flat face at +x), 32 segments of arc.
Shape FlatFrontPrismMesh(const FlatFrontPrism& prism);

/// Largest tilt from vertical, rad (20°), up to which a shell is taken as standing: its
/// cross-section at a height is its outline moved along the leaning axis; the stretch by 1/cos of
/// the tilt along that axis is neglected (under 0.5 mm up to 6°, 5.7 mm at 20°). Robots pitch and
/// roll a few degrees when they push each other, more when one is put into another; past 20° a
/// robot is falling over (the state checks' tipped) and the mesh test takes over. (At 5.7°, the
/// limit before, ODE's mesh-against-mesh test met two robots parting after a teleport, and its
/// normals, pointing up, rolled them over: about one robot a minute in the fast soak.)
inline constexpr double kUprightTilt = 0.35;

/// Contacts between two shells at poses `pa` and `pb` (the geometries' world poses), in ODE's
/// form: normal out of b into a (horizontal), depth, position, g1/g2 left for the caller.
/// Returns -1 when a shell leans more than kUprightTilt (use the general collider), else the
/// number of contacts written: 0 when apart, at most `max_contacts`; one per touching
/// cross-section at the bottom and the top of the shared height, two per level for two flat
/// faces pressed together; with fewer allowed, the deeper level's (its middle for one).
int CollideUprightPrisms(const FlatFrontPrism& a, const Pose& pa, const FlatFrontPrism& b, const Pose& pb,
                         int max_contacts, dContactGeom* out);

/// Contacts between an upright shell and a box standing upright (turned about z only: a field
/// wall, a goal's wall), found the same way: horizontal normal out of the box into the shell,
/// the least depth across. ODE's mesh-against-box test gives arbitrary normals for a shell
/// pushed into a thin wall (it is a hollow surface), which can throw a robot over the wall.
/// Returns -1 when the shell leans, the box is tilted, or the shell stands above (or below) the
/// box, overlapping it less in height than across (landing on a wall's top: the way out is
/// vertical); else as CollideUprightPrisms.
int CollideUprightPrismWithBox(const FlatFrontPrism& prism, const Pose& prism_pose, const Vec3& box_size,
                               const Pose& box_pose, int max_contacts, dContactGeom* out);

/// The contact between a shell, taken as the solid it stands for, and a sphere (the ball), at any
/// tilt: normal out of the shell toward the sphere's centre, depth, position on the shell's
/// surface; g1/g2 left for the caller. A centre inside the solid is pushed out through the side
/// (the round wall or the flat face), never through the top or the bottom: a ball cannot be
/// under a robot. ODE's sphere-against-mesh test sees the hollow surface only: a ball at 6.5 m/s
/// crosses a face in one 5 ms step, or slips under a lifted edge, and is then held inside.
/// Returns 1 with a contact, 0 when apart.
int CollideFlatFrontPrismWithSphere(const FlatFrontPrism& prism, const Pose& prism_pose, const Vec3& centre,
                                    double radius, dContactGeom* out);

}  // namespace ubersim::kernel
