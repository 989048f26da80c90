// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <sstream>
#include <string>

#include "ubersim/kernel/logging.hpp"
#include "ubersim/kernel/model.hpp"
#include "ubersim/kernel/plugin_registry.hpp"

// The shipped worlds (models/worlds/) loaded with the plugins built beside the tests, their
// transports dropped (no sockets): for tests that need real robots.
namespace ubersim::testing {

struct ShippedWorlds {
  std::ostringstream text;
  kernel::StreamLog log{text, LogLevel::kWarning};
  kernel::PluginRegistry registry{{UBERSIM_PLUGIN_BUILD_DIR}};
  // The worlds' transports are dropped below, so their parameters need no plugin to check them.
  kernel::ModelLoader loader{kernel::ModelLoader::DefaultSchemaDir(), [this](PluginKind k, const std::string& id) {
                               return k == PluginKind::kTransport ? std::string(R"({"type": "object"})")
                                                                  : registry.Find(k, id).schema_json;
                             }};

  /// models/worlds/NAME.yaml without its transports, optionally on another broadphase.
  kernel::WorldModel Load(const std::string& name, const std::string& broadphase = "") {
    kernel::WorldModel model = loader.LoadWorld(UBERSIM_SOURCE_DIR "/models/worlds/" + name + ".yaml");
    model.transports.clear();
    if (!broadphase.empty()) model.physics.broadphase = broadphase;
    return model;
  }
};

}  // namespace ubersim::testing
