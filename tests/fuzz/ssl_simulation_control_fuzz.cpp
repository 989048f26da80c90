// SPDX-License-Identifier: Apache-2.0
// Fuzz target: one datagram on the ssl_simulation transport's control port, handled as the
// transport does (OnControl in ssl_simulation_transport.cpp): parsed as a SimulatorCommand,
// mapped to events against the fuzz world, and answered with a SimulatorResponse.
#include <cstddef>
#include <cstdint>

#include "fuzz_checks.hpp"
#include "mapping.hpp"
#include "ssl_simulation_fixture.hpp"

namespace ssl = ubersim::ssl_simulation;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  SimulatorCommand command;
  SimulatorResponse response;
  if (auto e = ssl::ParseMessage(data, size, ubersim::fuzz::kMaxMessage, command)) {
    ssl::AppendErrors({*e}, response.mutable_errors());
    response.SerializeAsString();
    return 0;
  }
  for (bool wheels : {true, false}) {
    const ssl::Mapped m = ssl::MapSimulatorCommand(command, ubersim::fuzz::Where, ubersim::fuzz::Options(wheels));
    for (const ssl::WireError& e : m.errors) ubersim::fuzz::Check(!e.code.empty(), "an error without a code");
    ubersim::fuzz::CheckFinite(m.events);
    response.Clear();
    ssl::AppendErrors(m.errors, response.mutable_errors());
    response.SerializeAsString();
  }
  return 0;
}
