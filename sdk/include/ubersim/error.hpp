// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <stdexcept>
#include <string>

#include "ubersim/export.hpp"

namespace ubersim {
inline namespace v1 {

/// Thrown by a plugin that cannot do what it is asked (bad parameters, impossible geometry);
/// the kernel reports it with the plugin's name and file and keeps the world.
class UBERSIM_SDK_API PluginError : public std::runtime_error {
 public:
  /// Creates the error with a message saying what went wrong and why.
  explicit PluginError(const std::string& what);
  ~PluginError() override;
};

/// Thrown when a parameter is missing or of the wrong type; says where it was in the model file.
class UBERSIM_SDK_API ParamError : public std::runtime_error {
 public:
  /// Creates the error; `what` already carries file:line:column and the key.
  explicit ParamError(const std::string& what);
  ~ParamError() override;
};

}  // namespace v1
}  // namespace ubersim
