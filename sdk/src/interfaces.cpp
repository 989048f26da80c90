// SPDX-License-Identifier: Apache-2.0
// Key functions of the SDK's interfaces: one home for their vtables and typeinfo, so that the
// kernel and every plugin agree on them across shared-library boundaries.
#include "ubersim/component.hpp"
#include "ubersim/error.hpp"
#include "ubersim/log.hpp"
#include "ubersim/scene.hpp"
#include "ubersim/transport.hpp"

namespace ubersim {
inline namespace v1 {

Log::~Log() = default;
RobotContext::~RobotContext() = default;
Component::~Component() = default;
Drive::~Drive() = default;
Dribbler::~Dribbler() = default;
Kicker::~Kicker() = default;
TransportContext::~TransportContext() = default;
Transport::~Transport() = default;
Body::~Body() = default;
Geom::~Geom() = default;
Joint::~Joint() = default;
SceneNode::~SceneNode() = default;

PluginError::PluginError(const std::string& what) : std::runtime_error(what) {}
PluginError::~PluginError() = default;
ParamError::ParamError(const std::string& what) : std::runtime_error(what) {}
ParamError::~ParamError() = default;

std::string_view ToString(LogLevel level) {
  switch (level) {
    case LogLevel::kDebug: return "debug";
    case LogLevel::kInfo: return "info";
    case LogLevel::kWarning: return "warning";
    case LogLevel::kError: return "error";
  }
  return "unknown";
}

}  // namespace v1
}  // namespace ubersim
