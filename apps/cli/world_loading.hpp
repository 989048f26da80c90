// SPDX-License-Identifier: Apache-2.0
// The commands' names for the shared world loading (apps/shared/world_loading.hpp: the Python
// package loads worlds the same way).
#pragma once

#include "shared/world_loading.hpp"

namespace ubersim::cli {

using apps::LoadedWorld;
using apps::LoadingFor;
using apps::LoadWorldWithPlugins;
using apps::WorldFileOf;
using apps::WorldLoading;

}  // namespace ubersim::cli
