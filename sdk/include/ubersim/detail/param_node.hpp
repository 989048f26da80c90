// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace ubersim {
inline namespace v1 {
namespace detail {

/// One value of a validated model-file tree, with where it was written. The kernel builds these
/// from YAML; plugins see them only through ParamView.
struct ParamNode {
  struct Member;
  /// What the value is.
  enum class Kind : std::uint8_t { kNull, kBool, kInt, kDouble, kString, kArray, kObject };

  Kind kind = Kind::kNull;                                  ///< type of the value
  bool boolean = false;                                     ///< kBool value
  std::int64_t integer = 0;                                 ///< kInt value
  double number = 0.0;                                      ///< kDouble value (also set for kInt)
  std::string text;                                         ///< kString value
  std::vector<ParamNode> items;                             ///< kArray elements
  std::vector<Member> members;                              ///< kObject members, in file order
  std::string file;                                         ///< source file ("" when built in code)
  int line = 0;                                             ///< 1-based line, 0 when unknown
  int column = 0;                                           ///< 1-based column, 0 when unknown
};

/// One member of an object. A struct of its own, not std::pair<std::string, ParamNode>: a pair
/// of the enclosing type cannot be instantiated while that type is still incomplete, which
/// clang (rightly) refuses.
struct ParamNode::Member {
  std::string key;   ///< the member's name
  ParamNode value;   ///< its value
};

}  // namespace detail
}  // namespace v1
}  // namespace ubersim
