// SPDX-License-Identifier: Apache-2.0
// Fuzz target: one datagram on the ssl_simulation transport's blue or yellow port, handled as
// the transport does (OnRobotControl in ssl_simulation_transport.cpp): parsed as a RobotControl,
// mapped to command events for that team, and answered with the commanded robots' feedback.
#include <cstddef>
#include <cstdint>
#include <optional>

#include "fuzz_checks.hpp"
#include "mapping.hpp"
#include "ssl_simulation_fixture.hpp"

namespace ssl = ubersim::ssl_simulation;
using ubersim::fuzz::Bridge;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  RobotControl control;
  if (auto e = ssl::ParseMessage(data, size, ubersim::fuzz::kMaxMessage, control)) {
    RobotControlResponse refusal;
    ssl::AppendErrors({*e}, refusal.mutable_errors());
    refusal.SerializeAsString();
    return 0;
  }
  const auto contact = [](const ubersim::RobotId& id) { return Bridge().Report(id); };
  for (ubersim::Team team : {ubersim::Team::kBlue, ubersim::Team::kYellow}) {
    for (bool wheels : {true, false}) {
      const ssl::MappedRobotControl m =
          ssl::MapRobotControl(control, team, ubersim::fuzz::Where, ubersim::fuzz::Options(wheels));
      ubersim::fuzz::Check(m.events.size() <= static_cast<std::size_t>(control.robot_commands_size()),
                           "more command events than commands");
      ubersim::fuzz::Check(m.commanded_ids.size() <= static_cast<std::size_t>(control.robot_commands_size()),
                           "more robots commanded than named");
      ubersim::fuzz::CheckFinite(m.events);
      ssl::BuildRobotControlResponse(m.commanded_ids, team, contact, m.errors).SerializeAsString();
    }
  }
  return 0;
}
