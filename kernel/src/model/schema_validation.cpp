// SPDX-License-Identifier: Apache-2.0
// Draft-04 JSON Schema validation of a located tree (RapidJSON), with plain-English errors at the
// offending value's file:line:column and key path.
#include <algorithm>
#include <string>
#include <vector>

#include <rapidjson/document.h>
#include <rapidjson/error/en.h>
#include <rapidjson/pointer.h>
#include <rapidjson/schema.h>
#include <rapidjson/stringbuffer.h>
#include <rapidjson/writer.h>

#include "model_internal.hpp"
#include "ubersim/kernel/model.hpp"

namespace ubersim::kernel {
namespace {

using detail::ParamNode;
using Kind = ParamNode::Kind;
using model_detail::Describe;
using model_detail::ErrorAt;
using model_detail::FormatNumber;
using model_detail::JoinKey;

rapidjson::Value ToJson(const ParamNode& n, rapidjson::Document::AllocatorType& a) {
  rapidjson::Value v;
  switch (n.kind) {
    case Kind::kNull: v.SetNull(); break;
    case Kind::kBool: v.SetBool(n.boolean); break;
    case Kind::kInt: v.SetInt64(n.integer); break;
    case Kind::kDouble: v.SetDouble(n.number); break;
    case Kind::kString:
      v.SetString(n.text.data(), static_cast<rapidjson::SizeType>(n.text.size()), a);
      break;
    case Kind::kArray:
      v.SetArray();
      for (const auto& item : n.items) v.PushBack(ToJson(item, a), a);
      break;
    case Kind::kObject:
      v.SetObject();
      for (const auto& [k, child] : n.members) {
        rapidjson::Value key(k.data(), static_cast<rapidjson::SizeType>(k.size()), a);
        v.AddMember(key, ToJson(child, a), a);
      }
      break;
  }
  return v;
}

std::string JsonText(const rapidjson::Value& v) {
  if (v.IsString()) return std::string(v.GetString(), v.GetStringLength());
  rapidjson::StringBuffer b;
  rapidjson::Writer<rapidjson::StringBuffer> w(b);
  v.Accept(w);
  return std::string(b.GetString(), b.GetSize());
}

std::string NumberText(const rapidjson::Value& v) {
  if (v.IsInt64()) return std::to_string(v.GetInt64());
  if (v.IsUint64()) return std::to_string(v.GetUint64());
  if (v.IsNumber()) return FormatNumber(v.GetDouble());
  return JsonText(v);
}

std::string ValueText(const ParamNode& n) {
  switch (n.kind) {
    case Kind::kInt: return std::to_string(n.integer);
    case Kind::kDouble: return FormatNumber(n.number);
    case Kind::kString: return "\"" + n.text + "\"";
    default: return Describe(n);
  }
}

const char* TypeWords(const std::string& t) {
  if (t == "number") return "a number";
  if (t == "integer") return "an integer";
  if (t == "string") return "a string";
  if (t == "boolean") return "true or false";
  if (t == "object") return "an object (key: value mapping)";
  if (t == "array") return "an array (list)";
  if (t == "null") return "null";
  return "a value of another type";
}

std::string ExpectedTypes(const rapidjson::Value* schema) {
  if (!schema || !schema->IsObject() || !schema->HasMember("type")) return "another type";
  const rapidjson::Value& t = (*schema)["type"];
  if (t.IsString()) return TypeWords(t.GetString());
  std::string out;
  if (t.IsArray()) {
    for (rapidjson::SizeType i = 0; i < t.Size(); ++i) {
      if (!t[i].IsString()) continue;
      if (!out.empty()) out += i + 1 == t.Size() ? " or " : ", ";
      out += TypeWords(t[i].GetString());
    }
  }
  return out.empty() ? "another type" : out;
}

std::vector<std::string> PropertyNames(const rapidjson::Value* schema) {
  std::vector<std::string> names;
  if (!schema || !schema->IsObject()) return names;
  const auto it = schema->FindMember("properties");
  if (it == schema->MemberEnd() || !it->value.IsObject()) return names;
  for (auto m = it->value.MemberBegin(); m != it->value.MemberEnd(); ++m) {
    names.emplace_back(m->name.GetString(), m->name.GetStringLength());
  }
  return names;
}

std::size_t EditDistance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] != b[j - 1] ? 1 : 0)});
    }
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

std::string UnknownKeyReason(const std::string& key, const std::vector<std::string>& allowed) {
  std::string reason = "unknown key '" + key + "'";
  if (allowed.empty()) return reason + " (no keys are allowed here)";
  reason += " (allowed: ";
  for (std::size_t i = 0; i < allowed.size(); ++i) reason += (i ? ", " : "") + allowed[i];
  reason += ")";
  std::string best;
  std::size_t best_d = 3;  // suggest only close matches
  for (const auto& a : allowed) {
    const std::size_t d = EditDistance(key, a);
    if (d < best_d) best_d = d, best = a;
  }
  if (!best.empty()) reason += "; did you mean '" + best + "'?";
  return reason;
}

bool BoolMember(const rapidjson::Value* s, const char* name) {
  if (!s || !s->IsObject()) return false;
  const auto it = s->FindMember(name);
  return it != s->MemberEnd() && it->value.IsBool() && it->value.GetBool();
}

const rapidjson::Value* Member(const rapidjson::Value* s, const char* name) {
  if (!s || !s->IsObject()) return nullptr;
  const auto it = s->FindMember(name);
  return it == s->MemberEnd() ? nullptr : &it->value;
}

std::string Plural(std::size_t n, const char* word) {
  return std::to_string(n) + " " + word + (n == 1 ? "" : "s");
}

// The value a schema's `default` gives, located where the object it is put in was written.
ParamNode DefaultNode(const rapidjson::Value& v, const ParamNode& where) {
  ParamNode n;
  n.file = where.file;
  n.line = where.line;
  n.column = where.column;
  if (v.IsBool()) {
    n.kind = Kind::kBool;
    n.boolean = v.GetBool();
  } else if (v.IsInt64()) {
    n.kind = Kind::kInt;
    n.integer = v.GetInt64();
    n.number = static_cast<double>(n.integer);
  } else if (v.IsNumber()) {
    n.kind = Kind::kDouble;
    n.number = v.GetDouble();
  } else if (v.IsString()) {
    n.kind = Kind::kString;
    n.text = v.GetString();
  } else if (v.IsArray()) {
    n.kind = Kind::kArray;
    for (const auto& item : v.GetArray()) n.items.push_back(DefaultNode(item, where));
  } else if (v.IsObject()) {
    n.kind = Kind::kObject;
    for (const auto& m : v.GetObject()) n.members.push_back({m.name.GetString(), DefaultNode(m.value, where)});
  }
  return n;
}

void FillDefaults(ParamNode& node, const rapidjson::Value& schema) {
  if (!schema.IsObject()) return;
  if (node.kind == Kind::kArray) {
    const auto items = schema.FindMember("items");
    if (items == schema.MemberEnd()) return;
    for (ParamNode& item : node.items) FillDefaults(item, items->value);
    return;
  }
  const auto properties = schema.FindMember("properties");
  if (node.kind != Kind::kObject || properties == schema.MemberEnd() || !properties->value.IsObject()) return;
  for (const auto& p : properties->value.GetObject()) {
    const std::string key = p.name.GetString();
    const auto member = std::find_if(node.members.begin(), node.members.end(),
                                     [&](const ParamNode::Member& m) { return m.key == key; });
    if (member != node.members.end()) {
      FillDefaults(member->value, p.value);
    } else if (p.value.IsObject() && p.value.HasMember("default")) {
      node.members.push_back({key, DefaultNode(p.value["default"], node)});
    }
  }
}

}  // namespace

ParamView WithSchemaDefaults(const ParamView& value, const std::string& schema_json,
                             const std::string& schema_label) {
  rapidjson::Document schema_doc;
  schema_doc.Parse(schema_json.c_str(), schema_json.size());
  if (schema_doc.HasParseError()) {
    throw ErrorAt(value, "the schema " + schema_label + " is not valid JSON: " +
                             rapidjson::GetParseError_En(schema_doc.GetParseError()));
  }
  auto filled = std::make_shared<ParamNode>(value.Node());
  FillDefaults(*filled, schema_doc);
  return ParamView(std::move(filled), value.Path());
}

void ValidateAgainstSchema(const ParamView& value, const std::string& schema_json,
                           const std::string& schema_label) {
  rapidjson::Document schema_doc;
  schema_doc.Parse(schema_json.c_str(), schema_json.size());
  if (schema_doc.HasParseError()) {
    throw ErrorAt(value, "the schema " + schema_label + " is not valid JSON: " +
                             rapidjson::GetParseError_En(schema_doc.GetParseError()) +
                             " (offset " + std::to_string(schema_doc.GetErrorOffset()) + ")");
  }
  if (!schema_doc.IsObject()) {
    throw ErrorAt(value, "the schema " + schema_label + " is not a JSON object");
  }
  const rapidjson::SchemaDocument schema(schema_doc);

  rapidjson::Document doc;
  const rapidjson::Value root = ToJson(value.Node(), doc.GetAllocator());
  rapidjson::SchemaValidator validator(schema);
  if (root.Accept(validator) && validator.IsValid()) return;

  const std::string keyword = validator.GetInvalidSchemaKeyword() ? validator.GetInvalidSchemaKeyword() : "";
  const rapidjson::Pointer doc_ptr = validator.GetInvalidDocumentPointer();
  const rapidjson::Value* s = validator.GetInvalidSchemaPointer().Get(schema_doc);

  // Walk the JSON pointer through the located tree to the offending value.
  ParamView at = value;
  ParamView parent = value;
  std::string last_token;
  for (std::size_t i = 0; i < doc_ptr.GetTokenCount(); ++i) {
    const auto& t = doc_ptr.GetTokens()[i];
    const std::string name(t.name, t.length);
    parent = at;
    last_token = name;
    if (at.IsObject() && at.Has(name)) {
      at = at[name];
    } else if (at.IsArray() && t.index != rapidjson::kPointerInvalidIndex && t.index < at.Size()) {
      at = at.At(t.index);
    } else {
      break;
    }
  }
  const ParamNode& n = at.Node();

  if (keyword == "additionalProperties") {
    throw ErrorAt(at, UnknownKeyReason(last_token, PropertyNames(s)));
  }
  if (keyword == "required") {
    if (const rapidjson::Value* req = Member(s, "required"); req && req->IsArray()) {
      for (rapidjson::SizeType i = 0; i < req->Size(); ++i) {
        if (!(*req)[i].IsString()) continue;
        const std::string k = (*req)[i].GetString();
        if (!at.Has(k)) throw ErrorAt(at, JoinKey(at.Path(), k), "missing required key '" + k + "'");
      }
    }
    throw ErrorAt(at, "a required key is missing");
  }
  if (keyword == "type") {
    throw ErrorAt(at, "expected " + ExpectedTypes(s) + ", got " + Describe(n));
  }
  if (keyword == "minimum" || keyword == "maximum") {
    const rapidjson::Value* limit = Member(s, keyword.c_str());
    const std::string lim = limit ? NumberText(*limit) : "?";
    const std::string v = ValueText(n);
    if (keyword == "minimum") {
      throw ErrorAt(at, BoolMember(s, "exclusiveMinimum")
                            ? "value " + v + " must be greater than " + lim
                            : "value " + v + " is below the minimum " + lim);
    }
    throw ErrorAt(at, BoolMember(s, "exclusiveMaximum") ? "value " + v + " must be less than " + lim
                                                        : "value " + v + " is above the maximum " + lim);
  }
  if (keyword == "multipleOf") {
    const rapidjson::Value* m = Member(s, "multipleOf");
    throw ErrorAt(at, "value " + ValueText(n) + " is not a multiple of " + (m ? NumberText(*m) : "?"));
  }
  if (keyword == "enum") {
    std::string allowed;
    if (const rapidjson::Value* e = Member(s, "enum"); e && e->IsArray()) {
      for (rapidjson::SizeType i = 0; i < e->Size(); ++i) allowed += (i ? ", " : "") + JsonText((*e)[i]);
    }
    throw ErrorAt(at, "value " + ValueText(n) + " is not allowed (allowed: " + allowed + ")");
  }
  if (keyword == "minLength" || keyword == "maxLength") {
    const rapidjson::Value* m = Member(s, keyword.c_str());
    const std::string lim = m ? NumberText(*m) : "?";
    throw ErrorAt(at, keyword == "minLength"
                          ? "string " + ValueText(n) + " is shorter than " + lim + " characters"
                          : "string " + ValueText(n) + " is longer than " + lim + " characters");
  }
  if (keyword == "pattern") {
    const rapidjson::Value* p = Member(s, "pattern");
    throw ErrorAt(at, "string " + ValueText(n) + " does not match the pattern " +
                          (p ? JsonText(*p) : std::string("?")));
  }
  if (keyword == "minItems" || keyword == "maxItems" || keyword == "items" ||
      keyword == "additionalItems") {
    const std::size_t count = at.Size();
    if (keyword == "minItems") {
      const rapidjson::Value* m = Member(s, "minItems");
      throw ErrorAt(at, "expected at least " + (m ? NumberText(*m) : "?") + " elements, got " +
                            std::to_string(count));
    }
    if (keyword == "maxItems") {
      const rapidjson::Value* m = Member(s, "maxItems");
      throw ErrorAt(at, "expected at most " + (m ? NumberText(*m) : "?") + " elements, got " +
                            std::to_string(count));
    }
    const rapidjson::Value* items = Member(s, "items");
    const std::size_t max = items && items->IsArray() ? items->Size() : 0;
    throw ErrorAt(at, "expected at most " + Plural(max, "element") + ", got " + std::to_string(count));
  }
  if (keyword == "uniqueItems") throw ErrorAt(at, "the elements must all be different");
  if (keyword == "minProperties" || keyword == "maxProperties") {
    const rapidjson::Value* m = Member(s, keyword.c_str());
    throw ErrorAt(at, std::string("expected ") + (keyword == "minProperties" ? "at least " : "at most ") +
                          (m ? NumberText(*m) : "?") + " keys, got " + std::to_string(at.Size()));
  }
  if (keyword == "dependencies") {
    if (const rapidjson::Value* deps = Member(s, "dependencies"); deps && deps->IsObject()) {
      for (auto d = deps->MemberBegin(); d != deps->MemberEnd(); ++d) {
        const std::string k = d->name.GetString();
        if (!at.Has(k) || !d->value.IsArray()) continue;
        for (rapidjson::SizeType i = 0; i < d->value.Size(); ++i) {
          if (!d->value[i].IsString()) continue;
          const std::string need = d->value[i].GetString();
          if (!at.Has(need)) {
            throw ErrorAt(at[k], "key '" + k + "' needs key '" + need + "' beside it");
          }
        }
      }
    }
    throw ErrorAt(at, "a key's dependencies are not met");
  }
  if (keyword == "patternProperties") throw ErrorAt(at, "key '" + last_token + "' is not allowed here");
  if (keyword == "not") throw ErrorAt(at, "value " + ValueText(n) + " is not allowed here");
  if (keyword == "allOf" || keyword == "anyOf" || keyword == "oneOf") {
    throw ErrorAt(at, "value does not match " +
                          std::string(keyword == "allOf" ? "all of" : keyword == "anyOf" ? "any of" : "exactly one of") +
                          " the alternatives of " + schema_label);
  }
  throw ErrorAt(at, "does not satisfy '" + keyword + "' of " + schema_label);
}

}  // namespace ubersim::kernel
