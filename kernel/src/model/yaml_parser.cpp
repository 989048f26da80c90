// SPDX-License-Identifier: Apache-2.0
// YAML text -> located ParamNode tree (yaml-cpp), with YAML 1.2 core-schema scalar typing.
#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <system_error>
#include <vector>

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include "model_internal.hpp"
#include "ubersim/kernel/model.hpp"

namespace ubersim::kernel {
namespace {

using detail::ParamNode;
using Kind = ParamNode::Kind;

constexpr int kMaxDepth = 200;
// Values after aliases are expanded. A shipped model has a few hundred; aliases of aliases can
// make a few lines stand for billions, which would take the loader all memory and time.
constexpr std::size_t kMaxValues = 100000;
// A model file is text of a few kB; this stops a file name like /dev/zero from filling memory.
constexpr std::size_t kMaxFileBytes = 16u << 20;

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
    if (++values_ > kMaxValues) {
      throw ModelError(file_, line, column, key, "more than " + std::to_string(kMaxValues) +
                                                     " values once aliases are expanded (aliases of aliases?)");
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
          out.members.push_back({name, Convert(value, kl, kc, path, depth + 1)});
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
  std::size_t values_ = 0;  // converted so far
};

// Counts a text's documents from yaml-cpp's event stream (nothing is built), stopping at the
// second one: all ParseYamlText needs to know.
class DocumentCounter final : public YAML::EventHandler {
 public:
  void OnDocumentStart(const YAML::Mark& mark) override { starts.push_back(mark); }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark&, YAML::anchor_t) override {}
  void OnScalar(const YAML::Mark&, const std::string&, YAML::anchor_t, const std::string&) override {}
  void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {}
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {}
  void OnMapEnd() override {}

  std::vector<YAML::Mark> starts;  // where each document began
};

}  // namespace

std::shared_ptr<const detail::ParamNode> ParseYamlText(const std::string& text,
                                                       const std::string& file) {
  const auto where = [&](const YAML::Mark& m, const std::string& why) {
    return ModelError(file, m.line >= 0 ? m.line + 1 : 0, m.column >= 0 ? m.column + 1 : 0, "", why);
  };
  YAML::Node doc;
  std::size_t documents = 0;
  try {
    // Not YAML::LoadAll: yaml-cpp 0.7 never consumes a stray ',' after a document's node (a file
    // that is just ","), and LoadAll then collects empty documents until memory runs out. Counting
    // first, at most three, finds that: a document starts where the one before it did.
    std::istringstream stream(text);
    YAML::Parser parser(stream);
    DocumentCounter counter;
    while (counter.starts.size() < 3 && parser.HandleNextDocument(counter)) {
    }
    const std::vector<YAML::Mark>& starts = counter.starts;
    for (std::size_t i = 1; i < starts.size(); ++i) {
      if (starts[i].pos != starts[i - 1].pos) continue;
      const auto at = static_cast<std::size_t>(std::max(starts[i].pos, 0));
      const char c = at < text.size() ? text[at] : '?';
      throw where(starts[i], std::string("YAML syntax error: unexpected '") + c + "'");
    }
    documents = starts.size();
    if (documents > 1) throw where(starts[1], "a model file holds one YAML document; a second one starts here");
    if (documents == 1) doc = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw where(e.mark, "YAML syntax error: " + e.msg);
  }
  Converter converter(file);
  if (documents == 0) {
    auto empty = std::make_shared<detail::ParamNode>();
    empty->file = file;
    empty->line = 1;
    empty->column = 1;
    return empty;
  }
  const YAML::Mark m = doc.Mark();
  const int line = m.line >= 0 ? m.line + 1 : 1;
  const int column = m.column >= 0 ? m.column + 1 : 1;
  return std::make_shared<const detail::ParamNode>(converter.Convert(doc, line, column, "", 0));
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
  std::string text;
  std::array<char, 65536> chunk;
  while (in.read(chunk.data(), chunk.size()) || in.gcount() > 0) {
    text.append(chunk.data(), static_cast<std::size_t>(in.gcount()));
    if (text.size() > kMaxFileBytes) {
      throw ModelError(name, 0, 0, "", "larger than " + std::to_string(kMaxFileBytes >> 20) +
                                           " MiB: not a model file");
    }
  }
  if (in.bad()) {
    throw ModelError(name, 0, 0, "", std::string("cannot read file: ") + std::strerror(errno));
  }
  return ParseYamlText(text, name);
}

}  // namespace ubersim::kernel
