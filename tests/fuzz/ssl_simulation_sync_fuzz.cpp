// SPDX-License-Identifier: Apache-2.0
// Fuzz target: the byte stream a client sends to the ssl_simulation transport's synchronous TCP
// port. It is split into length-delimited frames (DelimitedDecoder, as sync_server.cpp does), in
// three ways: all at once, byte by byte, and in uneven chunks; the frames must not depend on how
// TCP happened to cut the stream. Each frame is then read as a SimulationSyncRequest and its
// commands mapped (OnSync in ssl_simulation_transport.cpp) until the first that would close the
// connection.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "transport_common/delimited.hpp"
#include "fuzz_checks.hpp"
#include "mapping.hpp"
#include "ssl_simulation_fixture.hpp"
#include "ssl_simulation_synchronous.pb.h"

namespace {

namespace ssl = ubersim::ssl_simulation;
using ubersim::fuzz::Check;

// The frames of `stream` when it arrives in pieces of `chunk(i)` bytes, and whether it ended in
// a framing error.
template <typename Chunk>
std::vector<std::string> Frames(std::string_view stream, Chunk chunk, bool& failed) {
  ubersim::transport::DelimitedDecoder decoder(ubersim::fuzz::kMaxMessage);
  std::vector<std::string> frames;
  failed = false;
  std::size_t at = 0;
  for (std::size_t i = 0; at < stream.size() && !failed; ++i) {
    const std::size_t n = std::min(stream.size() - at, std::max<std::size_t>(1, chunk(i)));
    decoder.Append(stream.substr(at, n));
    at += n;
    for (;;) {
      std::string message, error;
      const auto status = decoder.Next(message, error);
      if (status == ubersim::transport::DelimitedDecoder::Status::kNeedMore) break;
      if (status == ubersim::transport::DelimitedDecoder::Status::kError) {
        Check(!error.empty(), "a framing error without a reason");
        // Final: asking again gives the same error.
        std::string again;
        Check(decoder.Next(message, again) == ubersim::transport::DelimitedDecoder::Status::kError && again == error,
              "a framing error is not final");
        failed = true;
        break;
      }
      Check(message.size() <= ubersim::fuzz::kMaxMessage, "a frame larger than the limit");
      frames.push_back(std::move(message));
    }
  }
  return frames;
}

// What the transport does with one request; false when it would close the connection.
bool Handle(const std::string& frame) {
  SimulationSyncRequest request;
  if (ssl::ParseMessage(frame.data(), frame.size(), ubersim::fuzz::kMaxMessage, request)) return false;
  SimulationSyncResponse response;
  std::vector<ssl::WireError> errors;
  const ssl::MappingOptions options = ubersim::fuzz::Options(true);
  if (request.has_simulator_command()) {
    const ssl::Mapped m = ssl::MapSimulatorCommand(request.simulator_command(), ubersim::fuzz::Where, options);
    ubersim::fuzz::CheckFinite(m.events);
    errors.insert(errors.end(), m.errors.begin(), m.errors.end());
  }
  if (request.has_robot_control()) {
    const ssl::MappedRobotControl m =
        ssl::MapRobotControl(request.robot_control(), ubersim::Team::kBlue, ubersim::fuzz::Where, options);
    ubersim::fuzz::CheckFinite(m.events);
    errors.insert(errors.end(), m.errors.begin(), m.errors.end());
  }
  ssl::AppendErrors(errors, response.mutable_robot_control_response()->mutable_errors());
  // The reply goes back framed; reading it back must give the same bytes.
  const std::string payload = response.SerializeAsString();
  ubersim::transport::DelimitedDecoder echo(std::max(ubersim::fuzz::kMaxMessage, payload.size()));
  echo.Append(ubersim::transport::EncodeDelimited(payload));
  std::string back, error;
  Check(echo.Next(back, error) == ubersim::transport::DelimitedDecoder::Status::kMessage && back == payload,
        "a framed reply does not read back");
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view stream(reinterpret_cast<const char*>(data), size);
  bool whole_failed = false, bytes_failed = false, chunks_failed = false;
  const auto whole = Frames(stream, [&](std::size_t) { return size; }, whole_failed);
  const auto bytes = Frames(stream, [](std::size_t) { return std::size_t{1}; }, bytes_failed);
  // Uneven pieces, taken from the stream itself: 1 to 64 bytes.
  const auto chunks = Frames(stream, [&](std::size_t i) { return size ? 1 + data[(i * 7) % size] % 64 : 1; },
                             chunks_failed);
  Check(whole == bytes && whole == chunks, "the frames depend on how the stream was cut");
  Check(whole_failed == bytes_failed && whole_failed == chunks_failed, "a framing error depends on the cut");
  for (const std::string& frame : whole) {
    if (!Handle(frame)) break;
  }
  return 0;
}
