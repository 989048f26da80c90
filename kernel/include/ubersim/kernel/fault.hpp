// SPDX-License-Identifier: Apache-2.0
// Plugin faults: a plugin that throws where it may not, or leaves non-finite values in the world.
// The kernel names the plugin and what it did, switches it off, puts back what it broke, and then
// either carries on or stops, as the world file's `on_plugin_fault` says (docs/reliability.md).
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "ubersim/events.hpp"
#include "ubersim/plugin_kind.hpp"

namespace ubersim::kernel {

/// What a world does after a plugin fault (the world file's `on_plugin_fault`).
enum class FaultPolicy {
  kDisable,  ///< switch the plugin off; the robot (or the world) carries on without it
  kStop,     ///< switch it off, finish the step, then stop stepping so the caller saves the state
};

/// Parses "disable" or "stop"; throws std::invalid_argument otherwise.
FaultPolicy ParseFaultPolicy(const std::string& name);
/// "disable" or "stop".
const char* ToString(FaultPolicy policy);

/// One fault: who, what, where and when.
struct PluginFault {
  std::optional<RobotId> robot;  ///< the robot whose part it was; empty for a transport
  PluginKind kind = PluginKind::kDrive;  ///< the plugin's kind
  std::string plugin;      ///< plugin id; empty when no plugin call can be blamed
  std::string file;        ///< the plugin's library file
  std::string phase;       ///< "Configure", "PreStep", "SetCommand", "contact", "Publish", …
  std::string what;        ///< the exception's text, or the non-finite value and where it was
  std::int64_t step = 0;   ///< the step it happened in (0 while the world is built)
  std::int64_t sim_time_ns = 0;  ///< simulated time at the start of that step, ns
  /// "robot blue 3 drive 'omni' (/…/libubersim_omni.so): PreStep threw: …"
  std::string Describe() const;
};

}  // namespace ubersim::kernel
