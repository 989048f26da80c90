// SPDX-License-Identifier: Apache-2.0
// FNV-1a 64, the kernel's one digest of bytes: state hashes, structure digests, model-file
// digests, robot-spec digests. Equal digests mean equal bytes (doubles bit for bit).
#pragma once

#include <cstddef>
#include <cstdint>

namespace ubersim::kernel {

/// FNV-1a 64's starting value.
inline constexpr std::uint64_t kFnv1aOffset = 1469598103934665603ULL;

/// Folds `n` bytes at `data` into `h` (start from kFnv1aOffset).
inline void Fnv1a(std::uint64_t& h, const void* data, std::size_t n) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < n; ++i) {
    h ^= p[i];
    h *= 1099511628211ULL;
  }
}

}  // namespace ubersim::kernel
