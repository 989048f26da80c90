// SPDX-License-Identifier: Apache-2.0
// ParamView: read-only access to a located parameter tree, with errors that say where.
#include "ubersim/params.hpp"

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <system_error>
#include <utility>

#include <rapidjson/error/en.h>
#include <rapidjson/reader.h>
#include <rapidjson/stringbuffer.h>
#include <rapidjson/writer.h>

namespace ubersim {
inline namespace v1 {
namespace {

using detail::ParamNode;
using Kind = ParamNode::Kind;

std::string FormatNumber(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

// "string \"abc\"", "integer 3", "number 1.5", "bool true", "null", "an array", "an object".
std::string Describe(const ParamNode& n) {
  switch (n.kind) {
    case Kind::kNull: return "null";
    case Kind::kBool: return n.boolean ? "bool true" : "bool false";
    case Kind::kInt: return "integer " + std::to_string(n.integer);
    case Kind::kDouble: return "number " + FormatNumber(n.number);
    case Kind::kString: {
      std::string s = n.text.size() > 40 ? n.text.substr(0, 40) + "…" : n.text;
      return "string \"" + s + "\"";
    }
    case Kind::kArray: return "an array";
    case Kind::kObject: return "an object";
  }
  return "a value";
}

std::string Locate(const std::string& file, int line, int column) {
  if (file.empty() && line <= 0) return "<unknown>";
  std::string out = file.empty() ? "<unknown>" : file;
  if (line > 0) out += ":" + std::to_string(line) + ":" + std::to_string(column > 0 ? column : 1);
  return out;
}

std::string MemberPath(const std::string& base, std::string_view key) {
  return base.empty() ? std::string(key) : base + "." + std::string(key);
}

const ParamNode* FindMember(const ParamNode& n, std::string_view key) {
  if (n.kind != Kind::kObject) return nullptr;
  for (const auto& [k, v] : n.members) {
    if (k == key) return &v;
  }
  return nullptr;
}

// --- JSON -> ParamNode (SAX, so each value gets its line and column) -------------------------

// Line starts of a text, to turn byte offsets into 1-based line/column.
class LineIndex {
 public:
  explicit LineIndex(std::string_view text) : text_(text) {
    starts_.push_back(0);
    for (std::size_t i = 0; i < text.size(); ++i) {
      if (text[i] == '\n') starts_.push_back(i + 1);
    }
  }
  std::pair<int, int> At(std::size_t offset) const {
    std::size_t lo = 0, hi = starts_.size();
    while (hi - lo > 1) {
      const std::size_t mid = (lo + hi) / 2;
      if (starts_[mid] <= offset) lo = mid; else hi = mid;
    }
    return {static_cast<int>(lo + 1), static_cast<int>(offset - starts_[lo] + 1)};
  }
  // Start of the JSON string token that ends (closing quote included) just before `end`.
  std::size_t StringStart(std::size_t end) const {
    if (end < 2) return 0;
    std::size_t i = end - 1;  // closing quote
    while (i > 0) {
      --i;
      if (text_[i] != '"') continue;
      std::size_t backslashes = 0;
      for (std::size_t j = i; j > 0 && text_[j - 1] == '\\'; --j) ++backslashes;
      if (backslashes % 2 == 0) return i;
    }
    return 0;
  }

 private:
  std::string_view text_;
  std::vector<std::size_t> starts_;
};

// A read-only stream over the text. Unlike rapidjson::StringStream it is not copied inside the
// reader, so Tell() in a handler is the offset just past the token that was read.
class TextStream {
 public:
  using Ch = char;
  explicit TextStream(std::string_view text) : text_(text) {}
  Ch Peek() const { return pos_ < text_.size() ? text_[pos_] : '\0'; }
  Ch Take() { return pos_ < text_.size() ? text_[pos_++] : '\0'; }
  std::size_t Tell() const { return pos_; }
  Ch* PutBegin() { return nullptr; }
  void Put(Ch) {}
  void Flush() {}
  std::size_t PutEnd(Ch*) { return 0; }

 private:
  std::string_view text_;
  std::size_t pos_ = 0;
};

class TreeBuilder : public rapidjson::BaseReaderHandler<rapidjson::UTF8<>, TreeBuilder> {
 public:
  TreeBuilder(const LineIndex& lines, const TextStream& stream, std::string source)
      : lines_(lines), stream_(stream), source_(std::move(source)) {}

  bool Null() { return Scalar(Make(Kind::kNull, 4)); }
  bool Bool(bool b) {
    ParamNode n = Make(Kind::kBool, b ? 4 : 5);
    n.boolean = b;
    return Scalar(std::move(n));
  }
  bool RawNumber(const char* str, rapidjson::SizeType length, bool) {
    ParamNode n = Make(Kind::kInt, length);
    const std::string_view s(str, length);
    const bool integral = s.find_first_of(".eE") == std::string_view::npos;
    std::int64_t i = 0;
    const auto r = std::from_chars(s.data(), s.data() + s.size(), i);
    if (integral && r.ec == std::errc() && r.ptr == s.data() + s.size()) {
      n.integer = i;
      n.number = static_cast<double>(i);
    } else {
      n.kind = Kind::kDouble;
      n.number = std::strtod(std::string(s).c_str(), nullptr);
      if (!std::isfinite(n.number)) {
        error_ = "number " + std::string(s) + " is out of range";
        error_line_ = n.line;
        error_column_ = n.column;
        return false;
      }
    }
    return Scalar(std::move(n));
  }
  bool String(const char* str, rapidjson::SizeType length, bool) {
    ParamNode n;
    n.kind = Kind::kString;
    n.text.assign(str, length);
    Locate(n, lines_.StringStart(stream_.Tell()));
    return Scalar(std::move(n));
  }
  bool StartObject() { return Open(Kind::kObject); }
  bool Key(const char* str, rapidjson::SizeType length, bool) {
    Frame& f = stack_.back();
    const std::string key(str, length);
    for (const auto& [k, v] : f.node.members) {
      if (k == key) {
        const auto [line, column] = lines_.At(lines_.StringStart(stream_.Tell()));
        error_ = "duplicate key '" + key + "' (first at line " + std::to_string(v.line) + ")";
        error_line_ = line;
        error_column_ = column;
        return false;
      }
    }
    f.key = key;
    f.key_offset = lines_.StringStart(stream_.Tell());
    return true;
  }
  bool EndObject(rapidjson::SizeType) { return Close(); }
  bool StartArray() { return Open(Kind::kArray); }
  bool EndArray(rapidjson::SizeType) { return Close(); }

  ParamNode TakeRoot() { return std::move(root_); }
  const std::string& error() const { return error_; }
  int error_line() const { return error_line_; }
  int error_column() const { return error_column_; }

 private:
  struct Frame {
    ParamNode node;
    std::string key;
    std::size_t key_offset = 0;
  };

  void Locate(ParamNode& n, std::size_t offset) const {
    const auto [line, column] = lines_.At(offset);
    n.file = source_;
    n.line = line;
    n.column = column;
  }
  ParamNode Make(Kind kind, std::size_t token_length) const {
    ParamNode n;
    n.kind = kind;
    const std::size_t end = stream_.Tell();
    Locate(n, end >= token_length ? end - token_length : 0);
    return n;
  }
  bool Open(Kind kind) {
    Frame f;
    f.node.kind = kind;
    Locate(f.node, stream_.Tell() > 0 ? stream_.Tell() - 1 : 0);
    stack_.push_back(std::move(f));
    return true;
  }
  bool Close() {
    ParamNode n = std::move(stack_.back().node);
    stack_.pop_back();
    return Scalar(std::move(n));
  }
  // Attaches a finished value to its parent (or makes it the root).
  bool Scalar(ParamNode n) {
    if (stack_.empty()) {
      root_ = std::move(n);
      return true;
    }
    Frame& f = stack_.back();
    if (f.node.kind == Kind::kArray) {
      f.node.items.push_back(std::move(n));
    } else {
      // A member is located at its key, as in YAML files.
      Locate(n, f.key_offset);
      f.node.members.push_back({std::move(f.key), std::move(n)});
    }
    return true;
  }

  const LineIndex& lines_;
  const TextStream& stream_;
  std::string source_;
  std::vector<Frame> stack_;
  ParamNode root_;
  std::string error_;
  int error_line_ = 0;
  int error_column_ = 0;
};

// --- ParamNode -> JSON text --------------------------------------------------------------------

void Write(const ParamNode& n, rapidjson::Writer<rapidjson::StringBuffer>& w) {
  switch (n.kind) {
    case Kind::kNull: w.Null(); break;
    case Kind::kBool: w.Bool(n.boolean); break;
    case Kind::kInt: w.Int64(n.integer); break;
    case Kind::kDouble:
      if (std::isfinite(n.number)) w.Double(n.number); else w.Null();
      break;
    case Kind::kString:
      w.String(n.text.data(), static_cast<rapidjson::SizeType>(n.text.size()));
      break;
    case Kind::kArray:
      w.StartArray();
      for (const auto& item : n.items) Write(item, w);
      w.EndArray();
      break;
    case Kind::kObject:
      w.StartObject();
      for (const auto& [k, v] : n.members) {
        w.Key(k.data(), static_cast<rapidjson::SizeType>(k.size()));
        Write(v, w);
      }
      w.EndObject();
      break;
  }
}

std::shared_ptr<const ParamNode> EmptyObject() {
  auto n = std::make_shared<ParamNode>();
  n->kind = Kind::kObject;
  return n;
}

}  // namespace

ParamView::ParamView() : root_(EmptyObject()), node_(root_.get()) {}

ParamView::ParamView(std::shared_ptr<const detail::ParamNode> root, std::string path)
    : root_(root ? std::move(root) : EmptyObject()), node_(root_.get()), path_(std::move(path)) {}

ParamView::ParamView(std::shared_ptr<const detail::ParamNode> root, const detail::ParamNode* node,
                     std::string path)
    : root_(std::move(root)), node_(node), path_(std::move(path)) {}

ParamView ParamView::FromJson(std::string_view json, std::string source) {
  const std::string text(json);
  const LineIndex lines(text);
  TextStream stream(text);
  TreeBuilder builder(lines, stream, source);
  rapidjson::Reader reader;
  const rapidjson::ParseResult ok =
      reader.Parse<rapidjson::kParseNumbersAsStringsFlag | rapidjson::kParseStopWhenDoneFlag>(
          stream, builder);
  if (!ok) {
    if (!builder.error().empty()) {
      throw ParamError(Locate(source, builder.error_line(), builder.error_column()) + ": " +
                       builder.error());
    }
    const auto [line, column] = lines.At(ok.Offset());
    throw ParamError(Locate(source, line, column) + ": invalid JSON: " +
                     rapidjson::GetParseError_En(ok.Code()));
  }
  // Only whitespace may follow the value.
  const std::size_t rest = text.find_first_not_of(" \t\r\n", stream.Tell());
  if (rest != std::string::npos) {
    const auto [line, column] = lines.At(rest);
    throw ParamError(Locate(source, line, column) +
                     ": invalid JSON: The document root must not be followed by other values.");
  }
  return ParamView(std::make_shared<const ParamNode>(builder.TakeRoot()), "");
}

bool ParamView::Has(std::string_view key) const { return FindMember(*node_, key) != nullptr; }

ParamView ParamView::operator[](std::string_view key) const {
  if (node_->kind != Kind::kObject) {
    throw Error("expected an object with key '" + std::string(key) + "', got " + Describe(*node_));
  }
  const ParamNode* child = FindMember(*node_, key);
  if (!child) {
    const std::string child_path = MemberPath(path_, key);
    throw ParamError(Location() + ": key '" + child_path + "': missing required key '" +
                     std::string(key) + "'");
  }
  return ParamView(root_, child, MemberPath(path_, key));
}

ParamView ParamView::At(std::size_t index) const {
  if (node_->kind != Kind::kArray) {
    throw Error("expected an array, got " + Describe(*node_));
  }
  if (index >= node_->items.size()) {
    throw Error("index " + std::to_string(index) + " is out of range (the array has " +
                std::to_string(node_->items.size()) + " elements)");
  }
  return ParamView(root_, &node_->items[index], path_ + "[" + std::to_string(index) + "]");
}

std::size_t ParamView::Size() const {
  if (node_->kind == Kind::kArray) return node_->items.size();
  if (node_->kind == Kind::kObject) return node_->members.size();
  return 0;
}

std::vector<std::string> ParamView::Keys() const {
  std::vector<std::string> keys;
  if (node_->kind != Kind::kObject) return keys;
  keys.reserve(node_->members.size());
  for (const auto& m : node_->members) keys.push_back(m.key);
  return keys;
}

bool ParamView::IsNull() const { return node_->kind == Kind::kNull; }
bool ParamView::IsBool() const { return node_->kind == Kind::kBool; }
bool ParamView::IsNumber() const {
  return node_->kind == Kind::kInt || node_->kind == Kind::kDouble;
}
bool ParamView::IsString() const { return node_->kind == Kind::kString; }
bool ParamView::IsArray() const { return node_->kind == Kind::kArray; }
bool ParamView::IsObject() const { return node_->kind == Kind::kObject; }

double ParamView::AsDouble() const {
  if (node_->kind == Kind::kInt) return static_cast<double>(node_->integer);
  if (node_->kind == Kind::kDouble) return node_->number;
  throw Error("expected a number, got " + Describe(*node_));
}

std::int64_t ParamView::AsInt() const {
  if (node_->kind == Kind::kInt) return node_->integer;
  throw Error("expected an integer, got " + Describe(*node_));
}

bool ParamView::AsBool() const {
  if (node_->kind == Kind::kBool) return node_->boolean;
  throw Error("expected true or false, got " + Describe(*node_));
}

std::string ParamView::AsString() const {
  if (node_->kind == Kind::kString) return node_->text;
  throw Error("expected a string, got " + Describe(*node_));
}

Vec3 ParamView::AsVec3() const {
  if (node_->kind != Kind::kArray || node_->items.size() != 3) {
    throw Error("expected an array of 3 numbers [x, y, z], got " +
                (node_->kind == Kind::kArray
                     ? "an array of " + std::to_string(node_->items.size()) + " elements"
                     : Describe(*node_)));
  }
  return Vec3(At(0).AsDouble(), At(1).AsDouble(), At(2).AsDouble());
}

std::vector<double> ParamView::AsDoubleArray() const {
  if (node_->kind != Kind::kArray) throw Error("expected an array of numbers, got " + Describe(*node_));
  std::vector<double> out;
  out.reserve(node_->items.size());
  for (std::size_t i = 0; i < node_->items.size(); ++i) out.push_back(At(i).AsDouble());
  return out;
}

double ParamView::GetDouble(std::string_view key, double fallback) const {
  return Has(key) ? (*this)[key].AsDouble() : fallback;
}

std::int64_t ParamView::GetInt(std::string_view key, std::int64_t fallback) const {
  return Has(key) ? (*this)[key].AsInt() : fallback;
}

bool ParamView::GetBool(std::string_view key, bool fallback) const {
  return Has(key) ? (*this)[key].AsBool() : fallback;
}

std::string ParamView::GetString(std::string_view key, std::string_view fallback) const {
  return Has(key) ? (*this)[key].AsString() : std::string(fallback);
}

std::string ParamView::Location() const { return Locate(node_->file, node_->line, node_->column); }

ParamError ParamView::Error(std::string_view message) const {
  std::string what = Location() + ": ";
  if (!path_.empty()) what += "key '" + path_ + "': ";
  what += message;
  return ParamError(what);
}

std::string ParamView::ToJson() const {
  rapidjson::StringBuffer buffer;
  rapidjson::Writer<rapidjson::StringBuffer> writer(buffer);
  Write(*node_, writer);
  return std::string(buffer.GetString(), buffer.GetSize());
}

}  // namespace v1
}  // namespace ubersim
