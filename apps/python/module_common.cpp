// SPDX-License-Identifier: Apache-2.0
#include "module_common.hpp"

#include <pybind11/stl.h>

#include <stdexcept>

#include "shared/trial_world.hpp"
#include "ubersim/kernel/snapshot.hpp"

namespace ubersim::python {

namespace {

kernel::PhysicsOverrides OverridesOf(const WorldSettings& s) {
  kernel::PhysicsOverrides o;
  o.profile = s.profile;
  for (const auto& [key_object, value] : s.physics) {
    const std::string key = py::str(key_object);
    if (key == "step") {
      o.step = value.cast<double>();
    } else if (key == "solver_iterations") {
      o.solver_iterations = value.cast<int>();
    } else if (key == "solver_iterations_without_ball") {
      o.solver_iterations_without_ball = value.cast<int>();
    } else if (key == "erp") {
      o.erp = value.cast<double>();
    } else if (key == "cfm") {
      o.cfm = value.cast<double>();
    } else if (key == "max_contacts") {
      o.max_contacts = value.cast<int>();
    } else if (key == "contact_surface_layer") {
      o.contact_surface_layer = value.cast<double>();
    } else if (key == "contact_max_correcting_velocity") {
      o.contact_max_correcting_velocity = value.cast<double>();
    } else if (key == "robot_contact_erp") {
      o.robot_contact_erp = value.cast<double>();
    } else if (key == "broadphase") {
      o.broadphase = value.cast<std::string>();
    } else {
      throw py::value_error("physics: unknown key '" + key +
                            "' (step, solver_iterations, solver_iterations_without_ball, erp, cfm, max_contacts, "
                            "contact_surface_layer, contact_max_correcting_velocity, robot_contact_erp, broadphase)");
    }
  }
  return o;
}

}  // namespace

apps::LoadedWorld LoadForPython(const WorldSettings& settings) {
  if (settings.profile) {
    kernel::PhysicsModel probe;
    if (!kernel::PhysicsProfile(*settings.profile, probe)) {
      throw py::value_error("unknown physics profile '" + *settings.profile + "'");
    }
  }
  const kernel::PhysicsOverrides overrides = OverridesOf(settings);
  const std::filesystem::path file = apps::WorldFileOf(settings.world);
  apps::LoadedWorld loaded{apps::LoadingFor({file}, settings.plugin_paths), {}};
  loaded.model = apps::LoadTrialWorld(loaded.loading.loader, file, overrides, settings.robot);
  if (settings.seed) loaded.model.seed = *settings.seed;
  loaded.model.transports.clear();  // no sockets: Python drives the world
  return loaded;
}

py::dict FieldDict(const FieldGeometry& f) {
  py::dict d;
  d["name"] = f.name;
  d["field_length"] = f.field_length;
  d["field_width"] = f.field_width;
  d["goal_width"] = f.goal_width;
  d["goal_depth"] = f.goal_depth;
  d["goal_height"] = f.goal_height;
  d["boundary_width"] = f.boundary_width;
  d["penalty_area_depth"] = f.penalty_area_depth;
  d["penalty_area_width"] = f.penalty_area_width;
  d["center_circle_radius"] = f.center_circle_radius;
  d["line_thickness"] = f.line_thickness;
  d["goal_center_to_penalty_mark"] = f.goal_center_to_penalty_mark;
  py::list lines, arcs;
  for (const FieldLine& l : f.lines) lines.append(py::make_tuple(l.x1, l.y1, l.x2, l.y2, l.thickness));
  for (const FieldArc& a : f.arcs) arcs.append(py::make_tuple(a.cx, a.cy, a.radius, a.a1, a.a2, a.thickness));
  d["lines"] = lines;
  d["arcs"] = arcs;
  return d;
}

py::bytes SaveWorld(const kernel::World& world) {
  std::string bytes;
  {
    OdeSection ode;
    bytes = kernel::EncodeSnapshot(world.Save());
  }
  return py::bytes(bytes);  // with the GIL again
}

void RestoreWorld(kernel::World& world, const std::string& bytes) {
  const kernel::SavedState state = kernel::DecodeSnapshot(bytes, "the snapshot given to restore");
  OdeSection ode;
  world.Restore(state);
}

std::mutex& OdeMutex() {
  static std::mutex ode;  // process-wide by nature: ODE's own state is
  return ode;
}

}  // namespace ubersim::python
