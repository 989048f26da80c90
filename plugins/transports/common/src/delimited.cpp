// SPDX-License-Identifier: Apache-2.0
#include "transport_common/delimited.hpp"

#include <cstdint>

namespace ubersim::transport {

namespace {
// A 32-bit length takes at most 5 varint bytes; anything longer cannot be a sane prefix.
constexpr std::size_t kMaxPrefixBytes = 5;
}  // namespace

DelimitedDecoder::Status DelimitedDecoder::Next(std::string& message, std::string& error) {
  if (failed_) {
    error = failure_;
    return Status::kError;
  }
  std::uint64_t length = 0;
  std::size_t used = 0;
  bool complete = false;
  while (used < buffer_.size()) {
    const auto byte = static_cast<std::uint8_t>(buffer_[used]);
    if (used == kMaxPrefixBytes) break;
    length |= static_cast<std::uint64_t>(byte & 0x7f) << (7 * used);
    ++used;
    if ((byte & 0x80) == 0) {
      complete = true;
      break;
    }
  }
  if (!complete) {
    if (used < kMaxPrefixBytes) return Status::kNeedMore;
    failed_ = true;
    failure_ = "length prefix longer than " + std::to_string(kMaxPrefixBytes) + " bytes";
    error = failure_;
    return Status::kError;
  }
  if (length > max_message_) {
    failed_ = true;
    failure_ = "message of " + std::to_string(length) + " bytes is larger than the limit of " +
               std::to_string(max_message_);
    error = failure_;
    return Status::kError;
  }
  if (buffer_.size() - used < length) return Status::kNeedMore;
  message.assign(buffer_, used, static_cast<std::size_t>(length));
  buffer_.erase(0, used + static_cast<std::size_t>(length));
  return Status::kMessage;
}

std::string EncodeDelimited(std::string_view payload) {
  std::string out;
  std::uint64_t n = payload.size();
  while (n >= 0x80) {
    out.push_back(static_cast<char>((n & 0x7f) | 0x80));
    n >>= 7;
  }
  out.push_back(static_cast<char>(n));
  out.append(payload);
  return out;
}

}  // namespace ubersim::transport
