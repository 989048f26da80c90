// SPDX-License-Identifier: Apache-2.0
#include "bare_ode_mirror.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>

#include "physics/scene_graph.hpp"
#include "world/world_attorney.hpp"

namespace ubersim::kernel::bench {
namespace {

constexpr unsigned long kCarpetBit = 1;  // the carpet (a plane)
constexpr unsigned long kOtherBit = 2;   // everything else

// What the near callback needs of a copied geometry.
struct GeomInfo {
  double mu = 0.5;
  double mu2 = -1.0;
  double bounce = 0.0;
  double bounce_velocity = 0.1;
  bool has_axis = false;
  Vec3 axis = Vec3::Zero();  // body frame
};

void CopyBody(dBodyID from, dBodyID to) {
  dMass m;
  dBodyGetMass(from, &m);
  dBodySetMass(to, &m);
  const dReal* p = dBodyGetPosition(from);
  dBodySetPosition(to, p[0], p[1], p[2]);
  dBodySetQuaternion(to, dBodyGetQuaternion(from));
  const dReal* v = dBodyGetLinearVel(from);
  dBodySetLinearVel(to, v[0], v[1], v[2]);
  const dReal* w = dBodyGetAngularVel(from);
  dBodySetAngularVel(to, w[0], w[1], w[2]);
  dBodySetGravityMode(to, dBodyGetGravityMode(from));
  dBodySetFiniteRotationMode(to, dBodyGetFiniteRotationMode(from));
  dBodySetAutoDisableFlag(to, 0);
}

dGeomID CopyShape(dGeomID g) {
  switch (dGeomGetClass(g)) {
    case dSphereClass: return dCreateSphere(nullptr, dGeomSphereGetRadius(g));
    case dBoxClass: {
      dVector3 l;
      dGeomBoxGetLengths(g, l);
      return dCreateBox(nullptr, l[0], l[1], l[2]);
    }
    case dCapsuleClass: {
      dReal r, len;
      dGeomCapsuleGetParams(g, &r, &len);
      return dCreateCapsule(nullptr, r, len);
    }
    case dCylinderClass: {
      dReal r, len;
      dGeomCylinderGetParams(g, &r, &len);
      return dCreateCylinder(nullptr, r, len);
    }
    case dPlaneClass: {
      dVector4 p;
      dGeomPlaneGetParams(g, p);
      return dCreatePlane(nullptr, p[0], p[1], p[2], p[3]);
    }
    case dTriMeshClass:
      // Mesh data is read-only during collision; both geometries may share it.
      return dCreateTriMesh(nullptr, dGeomTriMeshGetTriMeshDataID(g), nullptr, nullptr, nullptr);
    default:
      throw std::runtime_error("bare-ODE baseline: cannot copy ODE geometry class " +
                               std::to_string(dGeomGetClass(g)));
  }
}

// Which contacts a geometry's observers let through: with the carpet, with anything else.
std::pair<bool, bool> ProbeObservers(GeomImpl& g, GeomImpl* carpet, GeomImpl* other) {
  bool carpet_ok = true;
  bool other_ok = true;
  const Vec3 at = g.GetPose().position;
  for (const ContactHandler& h : g.observers()) {
    SurfaceMaterial s = g.Material();
    if (carpet) h(Contact{&g, carpet, false, at, Vec3::UnitZ(), 0.001}, s, carpet_ok);
    if (other) h(Contact{&g, other, false, at, Vec3::UnitX(), 0.001}, s, other_ok);
  }
  return {carpet_ok, other_ok};
}

void CopyJointParams(dJointID from, dJointID to, int type) {
  for (int param : {dParamLoStop, dParamHiStop, dParamVel, dParamFMax, dParamBounce, dParamCFM,
                    dParamStopERP, dParamStopCFM}) {
    if (type == dJointTypeHinge) dJointSetHingeParam(to, param, dJointGetHingeParam(from, param));
    if (type == dJointTypeSlider) dJointSetSliderParam(to, param, dJointGetSliderParam(from, param));
  }
}

}  // namespace

BareOdeMirror::BareOdeMirror(World& world, std::uint64_t seed)
    : world_(dWorldCreate()), space_(dHashSpaceCreate(nullptr)),
      contacts_(dJointGroupCreate(0)) {
  const dWorldID from = WorldAttorney::OdeWorld(world);
  dWorldID w = world_.get();
  dVector3 gravity;
  dWorldGetGravity(from, gravity);
  dWorldSetGravity(w, gravity[0], gravity[1], gravity[2]);
  dWorldSetERP(w, dWorldGetERP(from));
  dWorldSetCFM(w, dWorldGetCFM(from));
  const PhysicsModel& physics = world.model().physics;
  islands_.SetIterations(physics.solver_iterations, physics.IterationsWithoutBall());
  dWorldSetContactSurfaceLayer(w, dWorldGetContactSurfaceLayer(from));
  dWorldSetContactMaxCorrectingVel(w, dWorldGetContactMaxCorrectingVel(from));
  dWorldSetAutoDisableFlag(w, 0);
  dSpaceSetCleanup(space_.get(), 0);
  step_ = world.clock().step_seconds();
  max_contacts_ = world.model().physics.max_contacts;

  // Bodies, in scene order.
  std::map<dBodyID, dBodyID> body_of;
  WorldAttorney::Scene(world).Root().ForEachBody([&](BodyImpl& b) {
    bodies_.emplace_back(dBodyCreate(w));
    CopyBody(b.id(), bodies_.back().get());
    body_of[b.id()] = bodies_.back().get();
  });
  ball_ = body_of.at(WorldAttorney::Ball(world).id());
  // Newest first, as IslandStepper wants them: ODE's own list.
  for (auto b = bodies_.rbegin(); b != bodies_.rend(); ++b) body_ids_.push_back(b->get());
  for (const auto& [kernel, copy] : body_of) {
    if (kernel != WorldAttorney::Ball(world).id() && dBodyGetNumJoints(kernel) == 0) free_.push_back(Twin{kernel, copy});
  }
  // The list's order, not the map's (pointer) order: the same copy on every run.
  std::sort(free_.begin(), free_.end(), [&](const Twin& a, const Twin& b) {
    return std::find(body_ids_.begin(), body_ids_.end(), a.copy) < std::find(body_ids_.begin(), body_ids_.end(), b.copy);
  });
  ball_ids_.assign(1, ball_);
  kernel_ball_ = WorldAttorney::Ball(world).id();
  // The robots whose model asks for more iterations, as the kernel gives them.
  for (const RobotPlacement& p : world.model().robots) {
    if (p.model->min_solver_iterations <= 0) continue;
    NodeImpl* node = WorldAttorney::Scene(world).Find(std::string(ToString(p.id.team)) + "/" + std::to_string(p.id.id));
    if (auto* chassis = node ? dynamic_cast<BodyImpl*>(node->FindBody("chassis")) : nullptr) {
      demands_.push_back({body_of.at(chassis->id()), p.model->min_solver_iterations});
    }
  }

  // One carpet and one other static geometry to probe contact observers with.
  GeomImpl* carpet = nullptr;
  GeomImpl* wall = nullptr;
  WorldAttorney::Scene(world).Root().ForEachGeom([&](GeomImpl& g) {
    if (g.body()) return;
    if (dGeomGetClass(g.id()) == dPlaneClass) {
      if (!carpet) carpet = &g;
    } else if (!wall) {
      wall = &g;
    }
  });

  // Geometries with their offsets, surfaces and contact filters.
  WorldAttorney::Scene(world).Root().ForEachGeom([&](GeomImpl& g) {
    if (!g.collides()) return;
    auto [carpet_ok, other_ok] = ProbeObservers(g, carpet, wall);
    carpet_ok = carpet_ok && g.scope() != ContactScope::kNoPlanes;
    other_ok = other_ok && g.scope() != ContactScope::kPlanesOnly;
    if (!carpet_ok && !other_ok) return;
    dGeomID copy = CopyShape(g.id());
    geoms_.emplace_back(copy);
    if (g.body()) {
      dGeomSetBody(copy, body_of.at(g.body()->id()));
      if (dGeomIsOffset(g.id())) {
        const dReal* p = dGeomGetOffsetPosition(g.id());
        dGeomSetOffsetPosition(copy, p[0], p[1], p[2]);
        dQuaternion q;
        dGeomGetOffsetQuaternion(g.id(), q);
        dGeomSetOffsetQuaternion(copy, q);
      }
    } else if (dGeomGetClass(copy) != dPlaneClass) {
      const dReal* p = dGeomGetPosition(g.id());
      dGeomSetPosition(copy, p[0], p[1], p[2]);
      dQuaternion q;
      dGeomGetQuaternion(g.id(), q);
      dGeomSetQuaternion(copy, q);
    }
    const bool is_carpet = dGeomGetClass(copy) == dPlaneClass;
    dGeomSetCategoryBits(copy, is_carpet ? kCarpetBit : kOtherBit);
    dGeomSetCollideBits(copy, (carpet_ok ? kCarpetBit : 0) | (other_ok ? kOtherBit : 0));
    auto info = std::make_unique<GeomInfo>();
    const SurfaceMaterial& m = g.Material();
    info->mu = m.mu;
    info->mu2 = m.mu2;
    info->bounce = m.bounce;
    info->bounce_velocity = m.bounce_velocity;
    if (g.friction_axis()) {
      info->has_axis = true;
      info->axis = *g.friction_axis();
    }
    dGeomSetData(copy, info.release());
    dSpaceAdd(space_.get(), copy);
  });

  // Joints: walk the scene's nodes.
  std::function<void(const NodeImpl&)> walk = [&](const NodeImpl& node) {
    for (const auto& j : node.joints()) {
      const dJointID from_joint = j->id();
      const int type = dJointGetType(from_joint);
      dJointID to = nullptr;
      switch (type) {
        case dJointTypeHinge: to = dJointCreateHinge(w, nullptr); break;
        case dJointTypeSlider: to = dJointCreateSlider(w, nullptr); break;
        case dJointTypeFixed: to = dJointCreateFixed(w, nullptr); break;
        case dJointTypeBall: to = dJointCreateBall(w, nullptr); break;
        case dJointTypeUniversal: to = dJointCreateUniversal(w, nullptr); break;
        default: throw std::runtime_error("bare-ODE baseline: cannot copy ODE joint type " + std::to_string(type));
      }
      joints_.emplace_back(to);
      dBodyID b0 = dJointGetBody(from_joint, 0);
      dBodyID b1 = dJointGetBody(from_joint, 1);
      dJointAttach(to, b0 ? body_of.at(b0) : nullptr, b1 ? body_of.at(b1) : nullptr);
      dVector3 v;
      switch (type) {
        case dJointTypeHinge:
          dJointGetHingeAnchor(from_joint, v);
          dJointSetHingeAnchor(to, v[0], v[1], v[2]);
          dJointGetHingeAxis(from_joint, v);
          dJointSetHingeAxis(to, v[0], v[1], v[2]);
          CopyJointParams(from_joint, to, type);
          motors_.push_back(Motor{from_joint, to});
          break;
        case dJointTypeSlider:
          dJointGetSliderAxis(from_joint, v);
          dJointSetSliderAxis(to, v[0], v[1], v[2]);
          CopyJointParams(from_joint, to, type);
          break;
        case dJointTypeFixed: dJointSetFixed(to); break;
        case dJointTypeBall:
          dJointGetBallAnchor(from_joint, v);
          dJointSetBallAnchor(to, v[0], v[1], v[2]);
          break;
        case dJointTypeUniversal:
          dJointGetUniversalAnchor(from_joint, v);
          dJointSetUniversalAnchor(to, v[0], v[1], v[2]);
          dJointGetUniversalAxis1(from_joint, v);
          dJointSetUniversalAxis1(to, v[0], v[1], v[2]);
          dJointGetUniversalAxis2(from_joint, v);
          dJointSetUniversalAxis2(to, v[0], v[1], v[2]);
          break;
      }
    }
    for (const auto& child : node.children()) walk(*child);
  };
  walk(WorldAttorney::Scene(world).Root());
  limbs_ = FindLimbs(body_ids_);
  ode_seed_ = static_cast<unsigned long>(seed);
}

BareOdeMirror::~BareOdeMirror() {
  for (const OdeGeom& g : geoms_) delete static_cast<GeomInfo*>(dGeomGetData(g.get()));
  joints_.clear();  // before the bodies they attach
  geoms_.clear();
}

void BareOdeMirror::NearCallback(void* data, dGeomID a, dGeomID b) {
  static_cast<BareOdeMirror*>(data)->Collide(a, b);
}

void BareOdeMirror::Collide(dGeomID a, dGeomID b) {
  const dBodyID ba = dGeomGetBody(a);
  const dBodyID bb = dGeomGetBody(b);
  if (ba == bb) return;  // static-static, or two geometries of one body
  if (ba && bb && dAreConnectedExcluding(ba, bb, dJointTypeContact)) return;
  if (!(dGeomGetCategoryBits(a) & dGeomGetCollideBits(b)) ||
      !(dGeomGetCategoryBits(b) & dGeomGetCollideBits(a))) {
    return;
  }
  dContactGeom found[16];
  const int n = dCollide(a, b, std::min(max_contacts_, 16), found, sizeof(dContactGeom));
  if (n == 0) return;
  const auto* ia = static_cast<const GeomInfo*>(dGeomGetData(a));
  const auto* ib = static_cast<const GeomInfo*>(dGeomGetData(b));
  const GeomInfo* directional = ia->has_axis ? ia : (ib->has_axis ? ib : nullptr);
  const dGeomID directional_geom = ia->has_axis ? a : b;
  for (int i = 0; i < n; ++i) {
    dContact c{};
    c.geom = found[i];
    c.surface.mode = dContactApprox1;
    c.surface.mu = std::sqrt(ia->mu * ib->mu);
    if (directional) {
      const dBodyID body = dGeomGetBody(directional_geom);
      dVector3 axis;
      dBodyVectorToWorld(body, directional->axis.x(), directional->axis.y(), directional->axis.z(), axis);
      const Vec3 n3(c.geom.normal[0], c.geom.normal[1], c.geom.normal[2]);
      Vec3 dir(axis[0], axis[1], axis[2]);
      dir -= n3 * n3.dot(dir);
      if (dir.norm() > 1e-6) {
        dir.normalize();
        c.surface.mode |= dContactMu2 | dContactFDir1;
        c.fdir1[0] = dir.x();
        c.fdir1[1] = dir.y();
        c.fdir1[2] = dir.z();
        c.surface.mu = directional->mu;
        c.surface.mu2 = directional->mu2 < 0 ? directional->mu : directional->mu2;
      }
    }
    const double bounce = std::max(ia->bounce, ib->bounce);
    if (bounce > 0) {
      c.surface.mode |= dContactBounce;
      c.surface.bounce = bounce;
      c.surface.bounce_vel = std::max(ia->bounce_velocity, ib->bounce_velocity);
    }
    dJointAttach(dJointCreateContact(world_.get(), contacts_.get(), &c), ba, bb);
    ++last_contacts_;
  }
}

BareOdeMirror::BodyState BareOdeMirror::Read(dBodyID b) {
  BodyState s;
  const dReal* p = dBodyGetPosition(b);
  const dReal* q = dBodyGetQuaternion(b);
  const dReal* v = dBodyGetLinearVel(b);
  const dReal* w = dBodyGetAngularVel(b);
  std::copy(p, p + 3, s.begin());
  std::copy(q, q + 4, s.begin() + 3);
  std::copy(v, v + 3, s.begin() + 7);
  std::copy(w, w + 3, s.begin() + 10);
  return s;
}

void BareOdeMirror::Write(dBodyID b, const BodyState& s) {
  dBodySetPosition(b, s[0], s[1], s[2]);
  dBodySetQuaternion(b, &s[3]);
  dBodySetLinearVel(b, s[7], s[8], s[9]);
  dBodySetAngularVel(b, s[10], s[11], s[12]);
}

void BareOdeMirror::Record(bool ball_moved) {
  for (const Motor& m : motors_) {
    motor_log_.push_back(dJointGetHingeParam(m.kernel, dParamVel));
    motor_log_.push_back(dJointGetHingeParam(m.kernel, dParamFMax));
  }
  for (const Twin& t : free_) body_log_.push_back(Read(t.kernel));
  ball_moved_log_.push_back(ball_moved ? 1 : 0);
  if (ball_moved) body_log_.push_back(Read(kernel_ball_));
  ++recorded_;
}

std::chrono::steady_clock::duration BareOdeMirror::StepRecorded() {
  std::chrono::steady_clock::duration stepping{};
  std::size_t motor = 0, body = 0;
  for (std::size_t step = 0; step < recorded_; ++step) {
    for (const Motor& m : motors_) {
      dJointSetHingeParam(m.copy, dParamVel, motor_log_[motor++]);
      dJointSetHingeParam(m.copy, dParamFMax, motor_log_[motor++]);
    }
    for (const Twin& t : free_) Write(t.copy, body_log_[body++]);
    if (ball_moved_log_[step]) Write(ball_, body_log_[body++]);
    const auto t0 = std::chrono::steady_clock::now();
    Step();
    stepping += std::chrono::steady_clock::now() - t0;
  }
  recorded_ = 0;
  motor_log_.clear();
  body_log_.clear();
  ball_moved_log_.clear();
  return stepping;
}

void BareOdeMirror::Step() {
  last_contacts_ = 0;
  dSpaceCollide(space_.get(), this, &NearCallback);
  dRandSetSeed(ode_seed_);
  islands_.Step(world_.get(), body_ids_, ball_ids_, step_, limbs_, demands_);
  ode_seed_ = dRandGetSeed();
  dJointGroupEmpty(contacts_.get());
}

KernelCollisionCounts LastCollisionCounts(World& world) {
  const CollisionStats& s = WorldAttorney::Collision(world).stats();
  return {s.contacts, s.touching_pairs, s.narrow_tests};
}

}  // namespace ubersim::kernel::bench
