// SPDX-License-Identifier: Apache-2.0
#include "game_controller_link.hpp"

#include <optional>
#include <stdexcept>

#include <boost/asio.hpp>

#include "transport_common/delimited.hpp"

namespace ubersim::match {

namespace asio = boost::asio;
using asio::ip::tcp;

namespace {
constexpr std::size_t kMaxMessage = 1 << 20;  // a Referee with every event of a stage fits easily
}  // namespace

struct GameControllerLink::Impl {
  std::string address;
  std::chrono::milliseconds timeout;
  asio::io_context io;
  tcp::socket socket{io};
  transport::DelimitedDecoder decoder{kMaxMessage};
  std::vector<char> buffer = std::vector<char>(65536);

  // Runs io until `done` or the timeout; false on timeout (the operation is cancelled).
  bool RunUntil(const bool& done) {
    io.restart();
    io.run_for(timeout);
    if (done) return true;
    boost::system::error_code ignored;
    socket.cancel(ignored);
    io.restart();
    io.run();
    return false;
  }

  [[noreturn]] void Fail(const std::string& why) const {
    throw std::runtime_error("game controller " + address + ": " + why);
  }

  // Reads once (blocking up to the timeout); appends to the decoder.
  void ReadSome() {
    bool done = false;
    boost::system::error_code error;
    std::size_t n = 0;
    socket.async_read_some(asio::buffer(buffer), [&](const boost::system::error_code& e, std::size_t bytes) {
      error = e;
      n = bytes;
      done = true;
    });
    if (!RunUntil(done)) Fail("no answer within " + std::to_string(timeout.count()) + " ms");
    if (error == asio::error::eof || error == asio::error::connection_reset) {
      Fail("hung up (" + std::string(error == asio::error::eof ? "closed the connection" : "connection reset by peer") + ")");
    }
    if (error) Fail(error.message());
    decoder.Append(std::string_view(buffer.data(), n));
  }

  // Takes every whole message the decoder holds.
  void Take(std::vector<Referee>& out) {
    std::string message, error;
    for (;;) {
      const auto status = decoder.Next(message, error);
      if (status == transport::DelimitedDecoder::Status::kNeedMore) return;
      if (status == transport::DelimitedDecoder::Status::kError) Fail("broken framing: " + error);
      CiOutput output;
      // An unparsable message is skipped, as the game controller does with ours (§1.2).
      if (output.ParseFromString(message) && output.has_referee_msg()) out.push_back(output.referee_msg());
    }
  }
};

GameControllerLink::GameControllerLink(const std::string& address, std::chrono::milliseconds timeout)
    : impl_(std::make_unique<Impl>()) {
  impl_->address = address;
  impl_->timeout = timeout;
  const auto colon = address.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == address.size()) {
    impl_->Fail("not HOST:PORT");
  }
  const std::string host = address.substr(0, colon), port = address.substr(colon + 1);
  boost::system::error_code error;
  tcp::resolver resolver(impl_->io);
  const auto endpoints = resolver.resolve(host, port, error);
  if (error) impl_->Fail("cannot resolve: " + error.message());
  bool done = false;
  asio::async_connect(impl_->socket, endpoints, [&](const boost::system::error_code& e, const tcp::endpoint&) {
    error = e;
    done = true;
  });
  if (!impl_->RunUntil(done)) impl_->Fail("no connection within " + std::to_string(timeout.count()) + " ms");
  if (error) impl_->Fail("cannot connect: " + error.message() + " (is ssl-game-controller running with -timeAcquisitionMode ci?)");
  impl_->socket.set_option(tcp::no_delay(true));
}

GameControllerLink::~GameControllerLink() = default;

std::string GameControllerLink::Describe() const { return "game controller " + impl_->address + " (CI mode)"; }

std::vector<Referee> GameControllerLink::Exchange(const CiInput& input) {
  const std::string frame = transport::EncodeDelimited(input.SerializeAsString());
  boost::system::error_code error;
  asio::write(impl_->socket, asio::buffer(frame), error);
  if (error) impl_->Fail("cannot send: " + error.message());
  std::vector<Referee> out;
  // At least one output per input with a time stamp (§1.4), then whatever else has arrived.
  while (out.empty()) {
    impl_->ReadSome();
    impl_->Take(out);
  }
  while (impl_->socket.available(error) > 0 && !error) {
    impl_->ReadSome();
    impl_->Take(out);
  }
  return out;
}

}  // namespace ubersim::match
