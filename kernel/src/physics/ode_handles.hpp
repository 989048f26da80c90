// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <memory>

#include <ode/ode.h>

// RAII owners for every ODE handle the kernel creates. Nothing outside the kernel sees these.
namespace ubersim::kernel {

/// Keeps ODE initialised while any world exists (dInitODE2/dCloseODE are process-wide in ODE
/// itself; this reference count is the one place that knows).
class OdeLibrary {
 public:
  OdeLibrary();
  ~OdeLibrary();
  OdeLibrary(const OdeLibrary&) = delete;
  OdeLibrary& operator=(const OdeLibrary&) = delete;
};

/// Deleters for ODE's opaque handle types.
struct OdeWorldDeleter { void operator()(dxWorld* w) const { dWorldDestroy(w); } };
struct OdeSpaceDeleter { void operator()(dxSpace* s) const { dSpaceDestroy(s); } };
struct OdeBodyDeleter { void operator()(dxBody* b) const { dBodyDestroy(b); } };
struct OdeGeomDeleter { void operator()(dxGeom* g) const { dGeomDestroy(g); } };
struct OdeJointDeleter { void operator()(dxJoint* j) const { dJointDestroy(j); } };
struct OdeJointGroupDeleter { void operator()(dxJointGroup* g) const { dJointGroupDestroy(g); } };
struct OdeTriMeshDataDeleter {
  void operator()(dxTriMeshData* d) const { dGeomTriMeshDataDestroy(d); }
};

using OdeWorld = std::unique_ptr<dxWorld, OdeWorldDeleter>;          ///< owns a dWorldID
using OdeSpace = std::unique_ptr<dxSpace, OdeSpaceDeleter>;          ///< owns a dSpaceID
using OdeBody = std::unique_ptr<dxBody, OdeBodyDeleter>;             ///< owns a dBodyID
using OdeGeom = std::unique_ptr<dxGeom, OdeGeomDeleter>;             ///< owns a dGeomID
using OdeJoint = std::unique_ptr<dxJoint, OdeJointDeleter>;          ///< owns a dJointID
using OdeJointGroup = std::unique_ptr<dxJointGroup, OdeJointGroupDeleter>;  ///< owns a dJointGroupID
using OdeTriMeshData = std::unique_ptr<dxTriMeshData, OdeTriMeshDataDeleter>;  ///< owns mesh data

}  // namespace ubersim::kernel
