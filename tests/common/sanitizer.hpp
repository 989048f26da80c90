// SPDX-License-Identifier: Apache-2.0
#pragma once

// Whether this test binary is the suite's sanitizer pass (clang, AddressSanitizer: ./test.sh
// --sanitize), for the few checks that cannot hold there (valgrind cannot run it) or hold with
// that compiler's own values.
namespace ubersim::testing {

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kAddressSanitizer = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
inline constexpr bool kAddressSanitizer = true;
#else
inline constexpr bool kAddressSanitizer = false;
#endif
#else
inline constexpr bool kAddressSanitizer = false;
#endif

}  // namespace ubersim::testing
