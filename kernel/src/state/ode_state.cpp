// SPDX-License-Identifier: Apache-2.0
#include "state/ode_state.hpp"

#include "util/fnv1a.hpp"

#include <algorithm>
#include <cstring>
#include <unordered_map>

namespace ubersim::kernel {
namespace {

// Visits every node with its path, depth first in insertion order (ForEachBody's order).
template <typename F>
void Walk(const NodeImpl& node, const std::string& path, F& f) {
  f(node, path);
  for (const auto& c : node.children()) Walk(*c, path.empty() ? c->Name() : path + "/" + c->Name(), f);
}

std::string Join(const std::string& path, const std::string& name) { return path.empty() ? name : path + "/" + name; }

// The motor parameter of a joint that has one.
bool GetMotor(dJointID j, JointKind kind, int param, dReal& value) {
  switch (kind) {
    case JointKind::kHinge: value = dJointGetHingeParam(j, param); return true;
    case JointKind::kSlider: value = dJointGetSliderParam(j, param); return true;
    case JointKind::kUniversal: value = dJointGetUniversalParam(j, param); return true;
    default: return false;
  }
}

void SetMotor(dJointID j, JointKind kind, int param, dReal value) {
  switch (kind) {
    case JointKind::kHinge: dJointSetHingeParam(j, param, value); break;
    case JointKind::kSlider: dJointSetSliderParam(j, param, value); break;
    case JointKind::kUniversal: dJointSetUniversalParam(j, param, value); break;
    default: break;
  }
}

// The space the collision manager files geometries in; null with the scene-graph broadphase.
dSpaceID SpaceOf(const SceneGraph& graph) {
  dSpaceID space = nullptr;
  graph.Root().ForEachGeom([&](GeomImpl& g) {
    if (!space) space = dGeomGetSpace(g.id());
  });
  // A robot's parts sit in a space of their own inside the collision manager's.
  while (space && dGeomGetSpace(reinterpret_cast<dGeomID>(space))) {
    space = dGeomGetSpace(reinterpret_cast<dGeomID>(space));
  }
  return space;
}

// ODE's sweep-and-prune space keeps the geometries moved since the last collision in a list
// appended to as they move; its other spaces put each moved geometry at the front of theirs.
bool AppendsMoved(dSpaceID space) { return dSpaceGetClass(space) == dSweepAndPruneSpaceClass; }

// The body that moved an entry of a space's list this step, or null when it did not move: a
// geometry's enabled body; for a robot's space, the body of its first part (its parts are listed
// moved first, and a robot's bodies move together or not at all).
dBodyID MovedBodyOf(dGeomID entry) {
  if (dGeomIsSpace(entry)) {
    const dSpaceID s = reinterpret_cast<dSpaceID>(entry);
    return dSpaceGetNumGeoms(s) > 0 ? MovedBodyOf(dSpaceGetGeom(s, 0)) : nullptr;
  }
  const dBodyID b = dGeomGetBody(entry);
  return b && dBodyIsEnabled(b) ? b : nullptr;
}

// Appends to `moved`, in the order they moved, the bodies that moved the leading entries of
// `space`'s list; a robot's space contributes its own moved parts' bodies there, all at once
// (its place in the outer list is its first move; the order inside it, its parts' moves).
void CollectMoves(dSpaceID space, std::vector<dBodyID>& moved) {
  std::vector<dGeomID> entries;
  for (int i = 0, n = dSpaceGetNumGeoms(space); i < n; ++i) {
    const dGeomID g = dSpaceGetGeom(space, i);
    if (!MovedBodyOf(g)) break;
    entries.push_back(g);
  }
  if (!AppendsMoved(space)) std::reverse(entries.begin(), entries.end());
  for (dGeomID g : entries) {
    if (dGeomIsSpace(g)) {
      CollectMoves(reinterpret_cast<dSpaceID>(g), moved);
    } else {
      moved.push_back(dGeomGetBody(g));
    }
  }
}

void HashDouble(std::uint64_t& h, double v) { Fnv1a(h, &v, sizeof v); }

void HashText(std::uint64_t& h, const std::string& s) {
  Fnv1a(h, s.data(), s.size());
  const unsigned char end = 0xff;  // ends the string: "ab","c" differs from "a","bc"
  Fnv1a(h, &end, 1);
}

}  // namespace

void CaptureOdeState(const SceneGraph& graph, SavedState& out) {
  out.bodies.clear();
  out.joints.clear();
  out.geom_collides.clear();
  out.moved_bodies.clear();
  std::unordered_map<dBodyID, std::uint32_t> body_index;
  auto visit = [&](const NodeImpl& node, const std::string& path) {
    for (const auto& b : node.bodies()) {
      const dBodyID id = b->id();
      SavedBody s;
      s.path = Join(path, b->Name());
      std::copy_n(dBodyGetPosition(id), 3, s.position.begin());
      std::copy_n(dBodyGetQuaternion(id), 4, s.quaternion.begin());
      std::copy_n(dBodyGetRotation(id), 12, s.rotation.begin());
      std::copy_n(dBodyGetLinearVel(id), 3, s.linear_velocity.begin());
      std::copy_n(dBodyGetAngularVel(id), 3, s.angular_velocity.begin());
      std::copy_n(dBodyGetForce(id), 3, s.force.begin());
      std::copy_n(dBodyGetTorque(id), 3, s.torque.begin());
      s.enabled = dBodyIsEnabled(id) != 0;
      body_index[id] = static_cast<std::uint32_t>(out.bodies.size());
      out.bodies.push_back(std::move(s));
    }
    for (const auto& j : node.joints()) {
      SavedJoint s;
      s.path = Join(path, j->Name());
      dReal v = 0;
      if (GetMotor(j->id(), j->Kind(), dParamVel, v)) s.motor_velocity = v;
      if (GetMotor(j->id(), j->Kind(), dParamFMax, v)) s.motor_max_effort = v;
      if (const dJointFeedback* fb = dJointGetFeedback(j->id())) {
        const dReal* parts[] = {fb->f1, fb->t1, fb->f2, fb->t2};
        for (int k = 0; k < 4; ++k) std::copy_n(parts[k], 3, s.feedback.begin() + 3 * k);
      }
      out.joints.push_back(std::move(s));
    }
    for (const auto& g : node.geoms()) out.geom_collides.push_back(g->collides());
  };
  Walk(graph.Root(), "", visit);

  // The space's order: at a step boundary the geometries ODE moved in the step (those of every
  // enabled body) lead dSpaceGetGeom's order, in the order of their moves, backwards where the
  // space puts moved ones at its front. Recorded as the bodies in move order.
  const dSpaceID space = SpaceOf(graph);
  if (!space) return;
  std::vector<dBodyID> moved;
  CollectMoves(space, moved);
  for (dBodyID b : moved) {
    const auto it = body_index.find(b);
    if (it == body_index.end()) continue;
    if (std::find(out.moved_bodies.begin(), out.moved_bodies.end(), it->second) == out.moved_bodies.end()) {
      out.moved_bodies.push_back(it->second);
    }
  }
}

void ApplyOdeState(SceneGraph& graph, const SavedState& in) {
  std::vector<BodyImpl*> bodies;
  std::vector<const JointImpl*> joints;
  std::vector<GeomImpl*> geoms;
  std::vector<std::string> body_paths, joint_paths;
  auto collect = [&](const NodeImpl& node, const std::string& path) {
    for (const auto& b : node.bodies()) {
      bodies.push_back(b.get());
      body_paths.push_back(Join(path, b->Name()));
    }
    for (const auto& j : node.joints()) {
      joints.push_back(j.get());
      joint_paths.push_back(Join(path, j->Name()));
    }
    for (const auto& g : node.geoms()) geoms.push_back(g.get());
  };
  Walk(graph.Root(), "", collect);
  // Check everything before writing anything: a mismatch leaves the world as it was.
  const auto differ = [](const char* what, std::size_t here, std::size_t saved) {
    return SnapshotError("the snapshot has " + std::to_string(saved) + " " + what + ", this world " +
                         std::to_string(here));
  };
  if (bodies.size() != in.bodies.size()) throw differ("bodies", bodies.size(), in.bodies.size());
  if (joints.size() != in.joints.size()) throw differ("joints", joints.size(), in.joints.size());
  if (geoms.size() != in.geom_collides.size()) throw differ("geometries", geoms.size(), in.geom_collides.size());
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    if (body_paths[i] != in.bodies[i].path) {
      throw SnapshotError("body " + std::to_string(i) + " is '" + in.bodies[i].path + "' in the snapshot, '" +
                          body_paths[i] + "' in this world");
    }
  }
  for (std::size_t i = 0; i < joints.size(); ++i) {
    if (joint_paths[i] != in.joints[i].path) {
      throw SnapshotError("joint " + std::to_string(i) + " is '" + in.joints[i].path + "' in the snapshot, '" +
                          joint_paths[i] + "' in this world");
    }
  }
  for (std::uint32_t i : in.moved_bodies) {
    if (i >= bodies.size()) throw SnapshotError("the snapshot's collision order names body " + std::to_string(i));
  }

  for (std::size_t i = 0; i < bodies.size(); ++i) {
    const SavedBody& s = in.bodies[i];
    const dBodyID b = bodies[i]->id();
    dBodySetPosition(b, s.position[0], s.position[1], s.position[2]);
    dBodySetQuaternion(b, s.quaternion.data());  // also tells the body's geometries they moved
    // dBodySetQuaternion normalises what it is given, which can change the last bit of a
    // quaternion the step had already normalised, and derives the matrix from the result. The
    // getters return ODE's own storage: put the saved bits there.
    std::copy(s.quaternion.begin(), s.quaternion.end(), const_cast<dReal*>(dBodyGetQuaternion(b)));
    std::copy(s.rotation.begin(), s.rotation.end(), const_cast<dReal*>(dBodyGetRotation(b)));
    dBodySetLinearVel(b, s.linear_velocity[0], s.linear_velocity[1], s.linear_velocity[2]);
    dBodySetAngularVel(b, s.angular_velocity[0], s.angular_velocity[1], s.angular_velocity[2]);
    dBodySetForce(b, s.force[0], s.force[1], s.force[2]);
    dBodySetTorque(b, s.torque[0], s.torque[1], s.torque[2]);
    if (s.enabled) {
      dBodyEnable(b);
    } else {
      dBodyDisable(b);
    }
  }
  for (std::size_t i = 0; i < joints.size(); ++i) {
    const SavedJoint& s = in.joints[i];
    const dJointID j = joints[i]->id();
    SetMotor(j, joints[i]->Kind(), dParamVel, s.motor_velocity);
    SetMotor(j, joints[i]->Kind(), dParamFMax, s.motor_max_effort);
    if (dJointFeedback* fb = dJointGetFeedback(j)) {
      dReal* parts[] = {fb->f1, fb->t1, fb->f2, fb->t2};
      for (int k = 0; k < 4; ++k) std::copy_n(s.feedback.begin() + 3 * k, 3, parts[k]);
    }
  }
  for (std::size_t i = 0; i < geoms.size(); ++i) geoms[i]->SetCollides(in.geom_collides[i]);

  // The space's order: everything clean as it now stands, then the saved bodies moved again in
  // the order ODE moved them, which rebuilds the moved ones' part of its order exactly. (The rest
  // keeps the build's order, which the original kept too for everything that collides: static
  // geometries never move, and the only bodies ODE does not move are disabled ones.)
  if (const dSpaceID space = SpaceOf(graph)) {
    dSpaceClean(space);
    for (std::uint32_t i : in.moved_bodies) {
      const dBodyID b = bodies[i]->id();
      const dReal* p = dBodyGetPosition(b);
      const dReal x = p[0], y = p[1], z = p[2];
      dBodySetPosition(b, x, y, z);
    }
  }
}

std::uint64_t SceneDigest(const SceneGraph& graph) {
  std::uint64_t h = kFnv1aOffset;
  auto visit = [&](const NodeImpl& node, const std::string& path) {
    HashText(h, path);
    for (const auto& b : node.bodies()) {
      HashText(h, b->Name());
      HashDouble(h, b->Mass());
    }
    for (const auto& j : node.joints()) {
      HashText(h, j->Name());
      HashDouble(h, static_cast<double>(j->Kind()));
    }
    for (const auto& g : node.geoms()) {
      HashText(h, g->Name());
      HashDouble(h, static_cast<double>(g->GetShape().kind));
    }
  };
  Walk(graph.Root(), "", visit);
  return h;
}

}  // namespace ubersim::kernel
