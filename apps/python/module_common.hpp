// SPDX-License-Identifier: Apache-2.0
// What the module's classes share: how a world is loaded for Python, the field as a dict, and
// the one lock every ODE call of the process takes.
#pragma once

#include <pybind11/pybind11.h>

#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "shared/world_loading.hpp"
#include "ubersim/kernel/world.hpp"

namespace ubersim::python {

namespace py = pybind11;

/// How a world is loaded from Python: the file or shipped name, and what replaces its settings.
struct WorldSettings {
  std::string world;                       ///< a file, or a shipped world's name
  std::vector<std::string> plugin_paths;   ///< searched after the world's own
  std::optional<std::uint64_t> seed;       ///< replaces the world file's
  std::optional<std::string> profile;      ///< a physics profile over the world file's
  py::dict physics;                        ///< physics keys over the profile (step, solver_iterations, …)
  std::optional<std::string> robot;        ///< a robot model file for every robot
};

/// The world of `settings`, with its plugins, its transports left out.
apps::LoadedWorld LoadForPython(const WorldSettings& settings);

/// The field's geometry as a dict (m, rad): the sizes, and the markings as tuples.
py::dict FieldDict(const FieldGeometry& field);

/// Held around every call into ODE: Debian's ODE keeps its random generator and trimesh cache
/// process-wide, so worlds of two threads step one after the other (docs/python.md).
std::mutex& OdeMutex();

/// A stretch of code that calls into ODE: releases the GIL, then takes OdeMutex (in that order: a
/// thread waiting for ODE must not hold the GIL the stepping thread may need).
struct OdeSection {
  py::gil_scoped_release release;
  std::lock_guard<std::mutex> ode{OdeMutex()};
};

/// `world`'s full state as snapshot bytes (the format of `ubersim run --snapshot-out`).
py::bytes SaveWorld(const kernel::World& world);
/// Puts snapshot `bytes` back into `world`; throws SnapshotError when they are not its snapshot.
void RestoreWorld(kernel::World& world, const std::string& bytes);

}  // namespace ubersim::python
