// SPDX-License-Identifier: Apache-2.0
#include "ubersim/kernel/model.hpp"

#include <charconv>
#include <utility>

#include "model_internal.hpp"

namespace ubersim::kernel {
namespace {

std::string Format(const std::string& file, int line, int column, const std::string& key,
                   const std::string& reason) {
  std::string out = file.empty() ? "<unknown>" : file;
  if (line > 0) out += ":" + std::to_string(line) + ":" + std::to_string(column > 0 ? column : 1);
  out += ": ";
  if (!key.empty()) out += "key '" + key + "': ";
  out += reason;
  return out;
}

}  // namespace

ModelError::ModelError(std::string file, int line, int column, std::string key, std::string reason)
    : std::runtime_error(Format(file, line, column, key, reason)),
      file_(std::move(file)),
      line_(line),
      column_(column),
      key_(std::move(key)),
      reason_(std::move(reason)) {}

namespace model_detail {

std::string FormatNumber(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

std::string Describe(const detail::ParamNode& n) {
  using Kind = detail::ParamNode::Kind;
  switch (n.kind) {
    case Kind::kNull: return "null";
    case Kind::kBool: return n.boolean ? "bool true" : "bool false";
    case Kind::kInt: return "integer " + std::to_string(n.integer);
    case Kind::kDouble: return "number " + FormatNumber(n.number);
    case Kind::kString: {
      const std::string s = n.text.size() > 40 ? n.text.substr(0, 40) + "…" : n.text;
      return "string \"" + s + "\"";
    }
    case Kind::kArray: return "an array";
    case Kind::kObject: return "an object";
  }
  return "a value";
}

ModelError ErrorAt(const ParamView& where, const std::string& reason) {
  return ErrorAt(where, where.Path(), reason);
}

ModelError ErrorAt(const ParamView& where, const std::string& key, const std::string& reason) {
  const detail::ParamNode& n = where.Node();
  return ModelError(n.file, n.line, n.column, key, reason);
}

std::string JoinKey(const std::string& base, const std::string& key) {
  return base.empty() ? key : base + "." + key;
}

}  // namespace model_detail
}  // namespace ubersim::kernel
