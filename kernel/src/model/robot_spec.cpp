// SPDX-License-Identifier: Apache-2.0
#include "robot_spec.hpp"

#include <cstring>
#include <sstream>

#include <rapidjson/document.h>

#include "util/fnv1a.hpp"
#include "model_internal.hpp"

namespace ubersim::kernel::model_detail {
namespace {

using detail::ParamNode;

struct FieldInfo {
  const char* name;
  std::optional<double> RobotSpec::*member;
  const char* unit;
};

// Every scalar field of RobotSpec, in declaration order.
constexpr FieldInfo kScalars[] = {
    {"radius", &RobotSpec::radius, "m"},
    {"height", &RobotSpec::height, "m"},
    {"mass", &RobotSpec::mass, "kg"},
    {"center_to_dribbler", &RobotSpec::center_to_dribbler, "m"},
    {"max_flat_kick_speed", &RobotSpec::max_flat_kick_speed, "m/s"},
    {"max_chip_kick_speed", &RobotSpec::max_chip_kick_speed, "m/s"},
    {"max_speed", &RobotSpec::max_speed, "m/s"},
    {"max_angular_speed", &RobotSpec::max_angular_speed, "rad/s"},
    {"max_acceleration", &RobotSpec::max_acceleration, "m/s²"},
    {"max_angular_acceleration", &RobotSpec::max_angular_acceleration, "rad/s²"},
    {"max_deceleration", &RobotSpec::max_deceleration, "m/s²"},
    {"max_angular_deceleration", &RobotSpec::max_angular_deceleration, "rad/s²"},
    {"dribbler_width", &RobotSpec::dribbler_width, "m"},
};

void Walk(const rapidjson::Value& schema, std::vector<std::string>& path, std::vector<SpecTarget>& out) {
  if (!schema.IsObject() || !schema.HasMember("properties") || !schema["properties"].IsObject()) return;
  const auto scale_of = [](const rapidjson::Value& v) {
    return v.HasMember("robot_spec_scale") && v["robot_spec_scale"].IsNumber() ? v["robot_spec_scale"].GetDouble()
                                                                                : 1.0;
  };
  for (const auto& m : schema["properties"].GetObject()) {
    const rapidjson::Value& sub = m.value;
    if (!sub.IsObject()) continue;
    path.emplace_back(m.name.GetString(), m.name.GetStringLength());
    if (sub.HasMember("robot_spec") && sub["robot_spec"].IsString()) {
      out.push_back(SpecTarget{sub["robot_spec"].GetString(), path, "", scale_of(sub)});
    }
    if (sub.HasMember("items") && sub["items"].IsObject() && sub["items"].HasMember("properties")) {
      for (const auto& item : sub["items"]["properties"].GetObject()) {
        if (item.value.IsObject() && item.value.HasMember("robot_spec") && item.value["robot_spec"].IsString()) {
          out.push_back(SpecTarget{item.value["robot_spec"].GetString(), path, item.name.GetString(),
                                   scale_of(item.value)});
        }
      }
    }
    Walk(sub, path, out);
    path.pop_back();
  }
}

ParamNode Number(double v, const std::string& source) {
  ParamNode n;
  n.kind = ParamNode::Kind::kDouble;
  n.number = v;
  n.file = source;
  return n;
}

ParamNode* Member(ParamNode& object, const std::string& key) {
  for (auto& m : object.members) {
    if (m.key == key) return &m.value;
  }
  return nullptr;
}


}  // namespace

std::vector<SpecTarget> SpecTargets(const std::string& schema_json) {
  std::vector<SpecTarget> out;
  rapidjson::Document d;
  d.Parse(schema_json.c_str(), schema_json.size());
  if (d.HasParseError()) return out;
  std::vector<std::string> path;
  Walk(d, path, out);
  return out;
}

std::vector<std::string> SetFields(const RobotSpec& spec) {
  std::vector<std::string> out;
  for (const FieldInfo& f : kScalars) {
    if (spec.*f.member) out.emplace_back(f.name);
    if (std::strcmp(f.name, "max_angular_deceleration") == 0 && spec.wheel_angles) out.emplace_back("wheel_angles");
  }
  return out;
}

std::optional<double> ScalarField(const RobotSpec& spec, const std::string& field) {
  for (const FieldInfo& f : kScalars) {
    if (field == f.name) return spec.*f.member;
  }
  return std::nullopt;
}

ParamNode WithEdit(const ParamNode& root, const SpecEdit& edit, const std::string& source) {
  ParamNode copy = root;
  ParamNode* at = &copy;
  for (const std::string& key : edit.path) {
    if (at->kind != ParamNode::Kind::kObject) {
      at->kind = ParamNode::Kind::kObject;
      at->members.clear();
    }
    ParamNode* next = Member(*at, key);
    if (!next) {
      ParamNode empty;
      empty.kind = ParamNode::Kind::kObject;
      empty.file = source;
      at->members.push_back(ParamNode::Member{key, empty});
      next = &at->members.back().value;
    }
    at = next;
  }
  if (edit.item) {
    if (at->kind != ParamNode::Kind::kArray || *edit.item >= at->items.size()) return copy;  // checked by the caller
    ParamNode& element = at->items[*edit.item];
    if (ParamNode* m = Member(element, edit.member)) {
      *m = Number(edit.value, source);
    } else {
      element.members.push_back(ParamNode::Member{edit.member, Number(edit.value, source)});
    }
    return copy;
  }
  *at = Number(edit.value, source);
  return copy;
}

std::string DescribeField(const RobotSpec& spec, const std::string& field) {
  std::ostringstream out;
  if (field == "wheel_angles" && spec.wheel_angles) {
    out << "wheel_angles [";
    for (std::size_t i = 0; i < spec.wheel_angles->size(); ++i) {
      out << (i ? ", " : "") << FormatNumber((*spec.wheel_angles)[i]);
    }
    out << "] rad";
    return out.str();
  }
  for (const FieldInfo& f : kScalars) {
    if (field == f.name && spec.*f.member) return field + " " + FormatNumber(*(spec.*f.member)) + " " + f.unit;
  }
  return field;
}

std::uint64_t SpecDigest(const RobotSpec& spec) {
  std::uint64_t h = kFnv1aOffset;
  for (const FieldInfo& f : kScalars) {
    const std::optional<double>& v = spec.*f.member;
    const char set = v ? 1 : 0;
    Fnv1a(h, &set, 1);
    if (v) Fnv1a(h, &*v, sizeof(double));
  }
  if (spec.wheel_angles) {
    for (double a : *spec.wheel_angles) Fnv1a(h, &a, sizeof a);
  }
  return h;
}

}  // namespace ubersim::kernel::model_detail
