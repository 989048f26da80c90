// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "ubersim/detail/param_node.hpp"
#include "ubersim/error.hpp"
#include "ubersim/export.hpp"
#include "ubersim/math.hpp"

namespace ubersim {
inline namespace v1 {

/// Read-only view of a validated parameter tree (a plugin's own block of a model file).
/// Values are SI. Every getter that fails throws ParamError naming file:line:column and the key path.
class UBERSIM_SDK_API ParamView {
 public:
  /// An empty object.
  ParamView();
  /// Views the whole tree `root`; `path` names it in error messages (e.g. "drive.params").
  explicit ParamView(std::shared_ptr<const detail::ParamNode> root, std::string path = "");
  /// Parses JSON text into a view (for tests and built-in defaults); throws ParamError.
  static ParamView FromJson(std::string_view json, std::string source = "<json>");

  /// True when this is an object with member `key`.
  bool Has(std::string_view key) const;
  /// The member `key` of this object; throws ParamError when missing.
  ParamView operator[](std::string_view key) const;
  /// Element `index` of this array; throws ParamError when out of range.
  ParamView At(std::size_t index) const;
  /// Number of elements (array) or members (object), 0 otherwise.
  std::size_t Size() const;
  /// Member names of an object, in file order.
  std::vector<std::string> Keys() const;

  /// True when the value is null / a bool / a number / a string / an array / an object.
  bool IsNull() const;
  bool IsBool() const;    ///< true for a boolean
  bool IsNumber() const;  ///< true for an integer or a real
  bool IsString() const;  ///< true for a string
  bool IsArray() const;   ///< true for an array
  bool IsObject() const;  ///< true for an object

  /// The value as a real; integers convert. Throws ParamError otherwise.
  double AsDouble() const;
  /// The value as an integer; throws ParamError for reals and others.
  std::int64_t AsInt() const;
  /// The value as a bool; throws ParamError otherwise.
  bool AsBool() const;
  /// The value as a string; throws ParamError otherwise.
  std::string AsString() const;
  /// An array of 3 numbers as a vector; throws ParamError otherwise.
  Vec3 AsVec3() const;
  /// An array of numbers; throws ParamError otherwise.
  std::vector<double> AsDoubleArray() const;

  /// Member `key` as a real, or `fallback` when absent.
  double GetDouble(std::string_view key, double fallback) const;
  /// Member `key` as an integer, or `fallback` when absent.
  std::int64_t GetInt(std::string_view key, std::int64_t fallback) const;
  /// Member `key` as a bool, or `fallback` when absent.
  bool GetBool(std::string_view key, bool fallback) const;
  /// Member `key` as a string, or `fallback` when absent.
  std::string GetString(std::string_view key, std::string_view fallback) const;

  /// Key path of this value from the root, e.g. "drive.wheels[2].angle_deg".
  const std::string& Path() const { return path_; }
  /// "file:line:column" of this value, or "<unknown>".
  std::string Location() const;
  /// Builds a ParamError "file:line:column: key 'path': message".
  ParamError Error(std::string_view message) const;
  /// The subtree as compact JSON (for schema validation and logs).
  std::string ToJson() const;
  /// The node itself (kernel use: schema validation).
  const detail::ParamNode& Node() const { return *node_; }

 private:
  ParamView(std::shared_ptr<const detail::ParamNode> root, const detail::ParamNode* node,
            std::string path);
  std::shared_ptr<const detail::ParamNode> root_;
  const detail::ParamNode* node_;
  std::string path_;
};

}  // namespace v1
}  // namespace ubersim
