// SPDX-License-Identifier: Apache-2.0
// Exports a plugin: the macros a plugin library uses once to register its class (Boost.DLL
// aliases around the descriptor of plugin_descriptor.hpp).
#pragma once

#include <cstdint>

#include <boost/config.hpp>
#include <boost/dll/alias.hpp>

#include "ubersim/plugin_descriptor.hpp"
#include "ubersim/plugin_kind.hpp"

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
