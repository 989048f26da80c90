// SPDX-License-Identifier: Apache-2.0
// A plugin from another plugin ABI: its descriptor function must never be called, so calling it
// aborts the process (the test would crash).
#include <cstdlib>

#include <ubersim/ubersim.hpp>

namespace fake {
const ubersim::PluginDescriptor* Descriptor() { std::abort(); }
const std::uint32_t kAbiWord = ((ubersim::kPluginAbiVersion + 1) << 16) | ubersim::kSdkVersionMajor;
}  // namespace fake
BOOST_DLL_ALIAS(fake::Descriptor, ubersim_plugin_v1)
BOOST_DLL_ALIAS(fake::kAbiWord, ubersim_abi_word)
