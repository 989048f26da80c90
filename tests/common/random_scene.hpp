// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <functional>
#include <random>
#include <string>

#include <ode/ode.h>

#include "physics/scene_graph.hpp"

// Random scenes of spheres, boxes and cylinders in nested nodes, some static, some on bodies
// (several geometries per body, several bodies per node), shared by the collision tests and the
// collision benchmark.
namespace ubersim::testing {

/// Size and density of a random scene.
struct RandomSceneSpec {
  int top_nodes = 6;           ///< children of the root
  int max_depth = 3;           ///< levels below the root
  int max_children = 3;        ///< children per node below the top
  int max_geoms = 3;           ///< geometries per node
  double extent = 1.0;         ///< positions in [-extent, extent]^3, m
  double max_size = 0.35;      ///< largest radius / half edge, m
};

/// Fills `graph` with a random scene drawn from `rng`.
inline void BuildRandomScene(kernel::SceneGraph& graph, std::mt19937_64& rng,
                             const RandomSceneSpec& spec = {}) {
  std::uniform_real_distribution<double> pos(-spec.extent, spec.extent);
  std::uniform_real_distribution<double> size(0.02, spec.max_size);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_int_distribution<int> shape_kind(0, 2);
  int counter = 0;
  auto random_quat = [&] {
    Quat q(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5);
    return q.norm() < 1e-6 ? Quat::Identity() : q.normalized();
  };
  auto random_shape = [&] {
    switch (shape_kind(rng)) {
      case 0: return Shape::Sphere(size(rng));
      case 1: return Shape::Box(2 * size(rng), 2 * size(rng), 2 * size(rng));
      default: return Shape::Cylinder(size(rng), 2 * size(rng));
    }
  };
  std::function<void(SceneNode&, int)> fill = [&](SceneNode& node, int depth) {
    // A node is either static scenery or one or two moving parts.
    const bool is_static = unit(rng) < 0.25;
    Body* bodies[2] = {nullptr, nullptr};
    if (!is_static) {
      const int n_bodies = unit(rng) < 0.3 ? 2 : 1;
      for (int i = 0; i < n_bodies; ++i) {
        BodySpec b;
        b.name = "body" + std::to_string(i);
        b.mass = MassSpec::Solid(Shape::Sphere(0.1), 1.0);
        b.pose = Pose{Vec3(pos(rng), pos(rng), pos(rng)), random_quat()};
        bodies[i] = &node.AddBody(b);
      }
    }
    std::uniform_int_distribution<int> n_geoms(1, spec.max_geoms);
    const int geoms = n_geoms(rng);
    for (int i = 0; i < geoms; ++i) {
      GeomSpec g;
      g.name = "g" + std::to_string(counter++);
      g.shape = random_shape();
      Body* body = is_static ? nullptr : bodies[(bodies[1] && unit(rng) < 0.5) ? 1 : 0];
      if (body) {
        g.offset = Pose{Vec3(pos(rng), pos(rng), pos(rng)) * 0.2, random_quat()};
      } else {
        g.offset = Pose{Vec3(pos(rng), pos(rng), pos(rng)), random_quat()};
      }
      node.AddGeom(g, body);
    }
    if (depth >= spec.max_depth) return;
    std::uniform_int_distribution<int> n_children(0, spec.max_children);
    const int children = n_children(rng);
    for (int i = 0; i < children; ++i) {
      fill(node.AddChild("n" + std::to_string(counter++)), depth + 1);
    }
  };
  for (int i = 0; i < spec.top_nodes; ++i) {
    fill(graph.Root().AddChild("top" + std::to_string(i)), 1);
  }
}

}  // namespace ubersim::testing
