// SPDX-License-Identifier: Apache-2.0
// YAML text -> located ParamNode tree (yaml-cpp), with YAML 1.2 core-schema scalar typing.
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <system_error>

#include <yaml-cpp/yaml.h>

#include "model_internal.hpp"
#include "ubersim/kernel/model.hpp"

namespace ubersim::kernel {
namespace {

using detail::ParamNode;
using Kind = ParamNode::Kind;

constexpr int kMaxDepth = 200;

bool IsDigit(char c) { return c >= '0' && c <= '9'; }

// [-+]?[0-9]+
bool LooksInteger(const std::string& s) {
  std::size_t i = (!s.empty() && (s[0] == '-' || s[0] == '+')) ? 1 : 0;
  if (i == s.size()) return false;
  for (; i < s.size(); ++i) {
    if (!IsDigit(s[i])) return false;
  }
  return true;
}

// [-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?  (YAML 1.2 core schema, finite floats)
bool LooksReal(const std::string& s) {
  std::size_t i = 0;
  if (i < s.size() && (s[i] == '-' || s[i] == '+')) ++i;
  std::size_t int_digits = 0, frac_digits = 0;
  while (i < s.size() && IsDigit(s[i])) ++i, ++int_digits;
  if (i < s.size() && s[i] == '.') {
    ++i;
    while (i < s.size() && IsDigit(s[i])) ++i, ++frac_digits;
  }
  if (int_digits == 0 && frac_digits == 0) return false;
  if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
    ++i;
    if (i < s.size() && (s[i] == '-' || s[i] == '+')) ++i;
    std::size_t exp_digits = 0;
    while (i < s.size() && IsDigit(s[i])) ++i, ++exp_digits;
    if (exp_digits == 0) return false;
  }
  return i == s.size();
}

// .inf, -.Inf, +.INF, .nan, .NaN, .NAN
bool IsYamlNonFinite(const std::string& s) {
  std::string t = s;
  if (!t.empty() && (t[0] == '-' || t[0] == '+')) t.erase(0, 1);
  return t == ".inf" || t == ".Inf" || t == ".INF" || s == ".nan" || s == ".NaN" || s == ".NAN";
}

class Converter {
 public:
  explicit Converter(std::string file) : file_(std::move(file)) {}

  ParamNode Convert(const YAML::Node& n, int line, int column, const std::string& key, int depth) {
    ParamNode out;
    out.file = file_;
    out.line = line;
    out.column = column;
    if (depth > kMaxDepth) {
      throw ModelError(file_, line, column, key, "nested more than " + std::to_string(kMaxDepth) +
                                                     " levels deep (a recursive alias?)");
    }
    switch (n.Type()) {
      case YAML::NodeType::Undefined:
      case YAML::NodeType::Null:
        out.kind = Kind::kNull;
        break;
      case YAML::NodeType::Scalar:
        Scalar(n, out, key);
        break;
      case YAML::NodeType::Sequence: {
        out.kind = Kind::kArray;
        std::size_t i = 0;
        for (const YAML::Node& item : n) {
          const auto [l, c] = MarkOf(item, line, column);
          out.items.push_back(Convert(item, l, c, key + "[" + std::to_string(i) + "]", depth + 1));
          ++i;
        }
        break;
      }
      case YAML::NodeType::Map: {
        out.kind = Kind::kObject;
        for (auto it = n.begin(); it != n.end(); ++it) {
          // Copies: the iterator hands out a temporary proxy pair.
          const YAML::Node k = it->first;
          const YAML::Node value = it->second;
          const auto [kl, kc] = MarkOf(k, line, column);
          if (!k.IsScalar()) {
            throw ModelError(file_, kl, kc, key,
                             k.IsNull() ? "empty key" : "a key must be a plain name, not a list or mapping");
          }
          const std::string name = k.Scalar();
          const std::string path = model_detail::JoinKey(key, name);
          for (const auto& [existing, value] : out.members) {
            if (existing == name) {
              throw ModelError(file_, kl, kc, path,
                               "duplicate key '" + name + "' (first at line " +
                                   std::to_string(value.line) + ")");
            }
          }
          // A member is located at its key: that is where a reader looks for it.
          out.members.emplace_back(name, Convert(value, kl, kc, path, depth + 1));
        }
        break;
      }
    }
    return out;
  }

 private:
  static std::pair<int, int> MarkOf(const YAML::Node& n, int line, int column) {
    const YAML::Mark m = n.Mark();
    if (m.line < 0 || m.column < 0) return {line, column};
    return {m.line + 1, m.column + 1};
  }

  void Scalar(const YAML::Node& n, ParamNode& out, const std::string& key) const {
    const std::string& text = n.Scalar();
    const std::string& tag = n.Tag();
    out.kind = Kind::kString;
    out.text = text;
    // "!" marks a quoted or block scalar: always a string. "!!str" says so explicitly.
    if (tag == "!" || tag == "tag:yaml.org,2002:str") return;
    if (tag != "?" && tag.rfind("tag:yaml.org,2002:", 0) != 0) {
      throw ModelError(file_, out.line, out.column, key, "unsupported YAML tag '" + tag + "'");
    }
    if (text == "true" || text == "True" || text == "TRUE") {
      out.kind = Kind::kBool;
      out.boolean = true;
    } else if (text == "false" || text == "False" || text == "FALSE") {
      out.kind = Kind::kBool;
      out.boolean = false;
    } else if (text == "null" || text == "Null" || text == "NULL" || text == "~") {
      out.kind = Kind::kNull;
    } else if (IsYamlNonFinite(text)) {
      throw ModelError(file_, out.line, out.column, key,
                       "'" + text + "' is not allowed: numbers must be finite");
    } else if (LooksInteger(text)) {
      const char* b = text.data() + (text[0] == '+' ? 1 : 0);
      std::int64_t v = 0;
      const auto r = std::from_chars(b, text.data() + text.size(), v);
      if (r.ec == std::errc() && r.ptr == text.data() + text.size()) {
        out.kind = Kind::kInt;
        out.integer = v;
        out.number = static_cast<double>(v);
      } else {
        SetReal(out, text, key);  // too large for a 64-bit integer
      }
    } else if (LooksReal(text)) {
      SetReal(out, text, key);
    }
  }

  void SetReal(ParamNode& out, const std::string& text, const std::string& key) const {
    errno = 0;
    const double v = std::strtod(text.c_str(), nullptr);
    if (!std::isfinite(v)) {
      throw ModelError(file_, out.line, out.column, key,
                       "number " + text + " is out of range: numbers must be finite");
    }
    out.kind = Kind::kDouble;
    out.number = v;
    out.text.clear();
  }

  std::string file_;
};

}  // namespace

std::shared_ptr<const detail::ParamNode> ParseYamlText(const std::string& text,
                                                       const std::string& file) {
  std::vector<YAML::Node> docs;
  try {
    docs = YAML::LoadAll(text);
  } catch (const YAML::Exception& e) {
    const int line = e.mark.line >= 0 ? e.mark.line + 1 : 0;
    const int column = e.mark.column >= 0 ? e.mark.column + 1 : 0;
    throw ModelError(file, line, column, "", "YAML syntax error: " + e.msg);
  }
  if (docs.size() > 1) {
    const YAML::Mark m = docs[1].Mark();
    throw ModelError(file, m.line >= 0 ? m.line + 1 : 0, m.column >= 0 ? m.column + 1 : 0, "",
                     "a model file holds one YAML document, this one has " +
                         std::to_string(docs.size()));
  }
  Converter converter(file);
  if (docs.empty()) {
    auto empty = std::make_shared<detail::ParamNode>();
    empty->file = file;
    empty->line = 1;
    empty->column = 1;
    return empty;
  }
  const YAML::Mark m = docs[0].Mark();
  const int line = m.line >= 0 ? m.line + 1 : 1;
  const int column = m.column >= 0 ? m.column + 1 : 1;
  return std::make_shared<const detail::ParamNode>(converter.Convert(docs[0], line, column, "", 0));
}

std::shared_ptr<const detail::ParamNode> ParseYamlFile(const std::filesystem::path& file) {
  const std::string name = file.string();
  std::error_code ec;
  if (std::filesystem::is_directory(file, ec)) {
    throw ModelError(name, 0, 0, "", std::string("cannot open file: ") + std::strerror(EISDIR));
  }
  errno = 0;
  std::ifstream in(file, std::ios::binary);
  if (!in) {
    const int err = errno ? errno : ENOENT;
    throw ModelError(name, 0, 0, "", std::string("cannot open file: ") + std::strerror(err));
  }
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) {
    throw ModelError(name, 0, 0, "", std::string("cannot read file: ") + std::strerror(errno));
  }
  return ParseYamlText(text.str(), name);
}

}  // namespace ubersim::kernel
