// SPDX-License-Identifier: Apache-2.0
// What a plugin library exports, as the kernel reads it: the descriptor, the build tag and the
// symbol names. Free of Boost.DLL; plugin.hpp adds the macros that export a descriptor.
#pragma once

#include <cstdint>

#include "ubersim/component.hpp"
#include "ubersim/plugin_kind.hpp"
#include "ubersim/transport.hpp"
#include "ubersim/version.hpp"

namespace ubersim {
inline namespace v1 {

/// Plain description a plugin library exports; its layout is frozen for an ABI version, and the
/// kernel reads `abi_word` and `descriptor_size` before touching anything else.
struct PluginDescriptor {
  std::uint32_t abi_word;         ///< kPluginAbiWord the plugin was built with
  std::uint32_t descriptor_size;  ///< sizeof(PluginDescriptor) in the plugin
  PluginKind kind;                ///< which interface `create` returns
  std::uint32_t sdk_major;        ///< SDK major built against
  std::uint32_t sdk_minor;        ///< SDK minor built against
  const char* id;                 ///< plugin id used in model files (lower_snake)
  const char* version;            ///< the plugin's own version
  const char* build_tag;          ///< C++ ABI of the build (see kBuildTag)
  const char* schema_json;        ///< JSON Schema (draft-04) of its parameter block
  void* (*create)();              ///< new instance, as a pointer to the kind's interface
  void (*destroy)(void*);         ///< deletes what create returned
};

/// The C++ library ABI a build uses; the kernel refuses a plugin whose tag differs from its own.
inline constexpr const char kBuildTag[] =
#if defined(_GLIBCXX_USE_CXX11_ABI) && _GLIBCXX_USE_CXX11_ABI
    "libstdc++-cxx11"
#elif defined(__GLIBCXX__)
    "libstdc++-cow"
#elif defined(_LIBCPP_VERSION)
    "libc++"
#else
    "unknown"
#endif
    ;

/// Name of the exported alias that returns the descriptor.
inline constexpr const char kDescriptorSymbol[] = "ubersim_plugin_v1";
/// Name of the exported alias of the ABI word, read first.
inline constexpr const char kAbiWordSymbol[] = "ubersim_abi_word";

namespace detail {
/// Interface type a kind's `create` returns.
template <PluginKind K> struct KindInterface;
template <> struct KindInterface<PluginKind::kDrive> { using type = Drive; };
template <> struct KindInterface<PluginKind::kDribbler> { using type = Dribbler; };
template <> struct KindInterface<PluginKind::kKicker> { using type = Kicker; };
template <> struct KindInterface<PluginKind::kTransport> { using type = Transport; };
}  // namespace detail

}  // namespace v1
}  // namespace ubersim
