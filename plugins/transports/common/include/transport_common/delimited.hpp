// SPDX-License-Identifier: Apache-2.0
// Length-delimited protobuf framing on a byte stream: each message is preceded by its size as a
// base-128 varint (protobuf's writeDelimitedTo, the game controller's TCP framing).
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace ubersim::transport {

/// Splits a byte stream into messages. Feed it what the socket delivered, then take messages
/// until it needs more. An error is final: the stream is out of step and must be closed.
class DelimitedDecoder {
 public:
  /// What Next found.
  enum class Status { kNeedMore, kMessage, kError };

  /// `max_message`: largest message accepted, bytes.
  explicit DelimitedDecoder(std::size_t max_message) : max_message_(max_message) {}
  /// Appends received bytes.
  void Append(std::string_view bytes) { buffer_.append(bytes); }
  /// The next message into `message`, or why the stream is broken into `error`.
  Status Next(std::string& message, std::string& error);
  /// Bytes received but not yet taken.
  std::size_t Buffered() const { return buffer_.size(); }

 private:
  std::size_t max_message_;
  std::string buffer_;
  bool failed_ = false;
  std::string failure_;
};

/// `payload` with its varint length in front.
std::string EncodeDelimited(std::string_view payload);

}  // namespace ubersim::transport
