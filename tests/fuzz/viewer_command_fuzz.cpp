// SPDX-License-Identifier: Apache-2.0
// Fuzz target: one WebSocket message from a viewer page, handled as the viewer transport does
// (OnMessage in viewer_transport.cpp): decoded as a JSON command and answered. The answer must
// be a JSON object itself, whatever the page sent.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include <rapidjson/document.h>

#include "fuzz_checks.hpp"
#include "viewer_protocol.hpp"

using ubersim::fuzz::Check;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const ubersim::viewer::CommandLimits limits;  // the transport's defaults
  const ubersim::viewer::DecodedCommand c = ubersim::viewer::DecodeCommand(text, limits);
  Check(c.error.empty() || (c.events.empty() && !c.speed_factor && !c.paused),
        "a refused command still has effects");
  Check(!c.error.empty() || !c.events.empty(), "an accepted command without events");
  ubersim::fuzz::CheckFinite(c.events);
  const std::string reply = c.error.empty() ? ubersim::viewer::EncodeReply(c.cmd, c.id)
                                            : ubersim::viewer::EncodeReply(c.cmd, c.id, c.error);
  rapidjson::Document doc;
  doc.Parse(reply.data(), reply.size());
  Check(!doc.HasParseError() && doc.IsObject(), "the reply is not a JSON object");
  return 0;
}
