// SPDX-License-Identifier: Apache-2.0
// Data paths: where the running program finds its shipped models, schemas and default world.
#pragma once

#include <filesystem>

namespace ubersim::kernel {

/// Folder of the running executable (from /proc/self/exe).
std::filesystem::path ExecutableDir();

/// The folder holding models/ and schemas/: $UBERSIM_DATA_DIR, else <exe>/../share/ubersim
/// (installed), else the source tree the binary was built from. Throws std::runtime_error
/// listing what it tried when none has models/.
std::filesystem::path DataDir();

/// The world `ubersim run` starts without an argument: models/worlds/div-b.yaml.
std::filesystem::path DefaultWorldFile();

}  // namespace ubersim::kernel
