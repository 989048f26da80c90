// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>

#include <boost/config.hpp>
#include <boost/dll/alias.hpp>

#include "ubersim/component.hpp"
#include "ubersim/transport.hpp"
#include "ubersim/version.hpp"

namespace ubersim {
inline namespace v1 {

/// What a plugin library provides.
enum class PluginKind : std::uint32_t { kDrive = 1, kDribbler = 2, kKicker = 3, kTransport = 4 };

/// "drive", "dribbler", "kicker", "transport" or "unknown".
inline const char* ToString(PluginKind k) {
  switch (k) {
    case PluginKind::kDrive: return "drive";
    case PluginKind::kDribbler: return "dribbler";
    case PluginKind::kKicker: return "kicker";
    case PluginKind::kTransport: return "transport";
  }
  return "unknown";
}

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

/// Registers CLASS (default-constructible) as the plugin of this library. Use one of the four
/// kind-specific macros below, once per library.
#define UBERSIM_DETAIL_REGISTER_PLUGIN(KIND, CLASS, ID, VERSION, SCHEMA_JSON)                    \
  namespace ubersim_plugin_export {                                                             \
  using Interface = ::ubersim::detail::KindInterface<KIND>::type;                               \
  static void* Create() { return static_cast<Interface*>(new CLASS()); }                        \
  static void Destroy(void* p) { delete static_cast<Interface*>(p); }                           \
  static const ::ubersim::PluginDescriptor kDescriptor{                                         \
      ::ubersim::kPluginAbiWord, sizeof(::ubersim::PluginDescriptor), KIND,                     \
      ::ubersim::kSdkVersionMajor, ::ubersim::kSdkVersionMinor, ID, VERSION,                    \
      ::ubersim::kBuildTag, SCHEMA_JSON, &Create, &Destroy};                                    \
  const ::ubersim::PluginDescriptor* Descriptor() { return &kDescriptor; }                      \
  const std::uint32_t kAbiWord = ::ubersim::kPluginAbiWord;                                     \
  }                                                                                             \
  BOOST_DLL_ALIAS(ubersim_plugin_export::Descriptor, ubersim_plugin_v1)                         \
  BOOST_DLL_ALIAS(ubersim_plugin_export::kAbiWord, ubersim_abi_word)

/// Registers a drive plugin: class, id ("omni"), version ("1.0.0"), schema JSON text.
#define UBERSIM_REGISTER_DRIVE(CLASS, ID, VERSION, SCHEMA_JSON) \
  UBERSIM_DETAIL_REGISTER_PLUGIN(::ubersim::PluginKind::kDrive, CLASS, ID, VERSION, SCHEMA_JSON)
/// Registers a dribbler plugin.
#define UBERSIM_REGISTER_DRIBBLER(CLASS, ID, VERSION, SCHEMA_JSON) \
  UBERSIM_DETAIL_REGISTER_PLUGIN(::ubersim::PluginKind::kDribbler, CLASS, ID, VERSION, SCHEMA_JSON)
/// Registers a kicker plugin.
#define UBERSIM_REGISTER_KICKER(CLASS, ID, VERSION, SCHEMA_JSON) \
  UBERSIM_DETAIL_REGISTER_PLUGIN(::ubersim::PluginKind::kKicker, CLASS, ID, VERSION, SCHEMA_JSON)
/// Registers a transport plugin.
#define UBERSIM_REGISTER_TRANSPORT(CLASS, ID, VERSION, SCHEMA_JSON) \
  UBERSIM_DETAIL_REGISTER_PLUGIN(::ubersim::PluginKind::kTransport, CLASS, ID, VERSION, SCHEMA_JSON)
