// SPDX-License-Identifier: Apache-2.0
// What `ubersim run` takes from its command line beside the world file, as the league's
// simulators take it (ER-Force's simulator-cli: --realism, -g): a realism preset, a field, the
// transports' ports, loopback only.
#pragma once

#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "ubersim/kernel/model.hpp"
#include "ubersim/kernel/plugin_registry.hpp"

namespace ubersim::kernel {

/// A command-line value that does not fit the world (an unknown preset or field, a port for a
/// transport the world does not start): a usage error, its message names the flag.
class OverrideError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The command line's changes to a world.
struct RunOverrides {
  std::string realism;  ///< ÜberSim's preset (ideal, 2003, realistic) or the league's (None, Friendly, RC2021, Realistic)
  std::string field;    ///< a field by name (div-a, div-b; ER-Force's 2020, 2023 and 2023B too)
  /// Ports by flag: "vision", "control", "blue", "yellow", "grsim", "viewer".
  std::map<std::string, int> ports;
  std::string vision_address;  ///< the vision's multicast group (or unicast address)
  bool local_only = false;     ///< every transport on loopback
  /// The port the viewer listens for Referee messages on (`--referee-port`, so that it shows the
  /// match the referee publishes there); nothing when the world starts no viewer.
  std::optional<int> viewer_referee_port;
};

/// Applies `overrides` to `world` (transport parameters checked against their plugins' schemas);
/// returns the lines to print once at start (notes on what the overrides changed).
/// Throws OverrideError or ModelError.
std::vector<std::string> ApplyRunOverrides(const RunOverrides& overrides, WorldModel& world,
                                           const ModelLoader& loader, PluginRegistry& registry);

}  // namespace ubersim::kernel
