// SPDX-License-Identifier: Apache-2.0
// The defaults in force are the ones the schemas document: for every shipped robot and world, each
// plugin (drive, dribbler, kicker, transport) gets, for every key its schema gives a `default` and
// the file leaves out, exactly that default in its parameters; the keys the file writes keep the
// file's values. A plugin's own C++ fallback is then never what decides.
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <rapidjson/document.h>

#include "ubersim/kernel/logging.hpp"
#include "ubersim/kernel/model.hpp"
#include "ubersim/kernel/plugin_registry.hpp"

namespace ubersim::kernel {
namespace {

namespace fs = std::filesystem;
using detail::ParamNode;

const ParamNode* Member(const ParamNode& node, const std::string& key) {
  if (node.kind != ParamNode::Kind::kObject) return nullptr;
  for (const auto& m : node.members) {
    if (m.key == key) return &m.value;
  }
  return nullptr;
}

bool SameValue(const ParamNode& a, const rapidjson::Value& b) {
  if (b.IsBool()) return a.kind == ParamNode::Kind::kBool && a.boolean == b.GetBool();
  if (b.IsNumber()) {
    return (a.kind == ParamNode::Kind::kInt || a.kind == ParamNode::Kind::kDouble) && a.number == b.GetDouble();
  }
  if (b.IsString()) return a.kind == ParamNode::Kind::kString && a.text == b.GetString();
  if (b.IsArray()) {
    if (a.kind != ParamNode::Kind::kArray || a.items.size() != b.Size()) return false;
    for (rapidjson::SizeType i = 0; i < b.Size(); ++i) {
      if (!SameValue(a.items[i], b[i])) return false;
    }
    return true;
  }
  if (b.IsObject()) {
    if (a.kind != ParamNode::Kind::kObject || a.members.size() != b.MemberCount()) return false;
    for (const auto& m : b.GetObject()) {
      const ParamNode* am = Member(a, m.name.GetString());
      if (!am || !SameValue(*am, m.value)) return false;
    }
    return true;
  }
  return false;
}

struct Checker {
  std::string who;  // "drive 'omni' in models/robots/…"
  int defaults = 0;  // keys the file left out that got the schema's default
  int written = 0;   // keys the file wrote that kept its value

  // `loaded` (the loader's parameters) against `raw` (the file's block) under `schema`.
  void Check(const ParamNode& loaded, const ParamNode* raw, const rapidjson::Value& schema, const std::string& path) {
    if (!schema.IsObject()) return;
    if (loaded.kind == ParamNode::Kind::kArray && schema.HasMember("items")) {
      for (std::size_t i = 0; i < loaded.items.size(); ++i) {
        const ParamNode* raw_item = raw && i < raw->items.size() ? &raw->items[i] : nullptr;
        Check(loaded.items[i], raw_item, schema["items"], path + "[" + std::to_string(i) + "]");
      }
      return;
    }
    if (!schema.HasMember("properties") || loaded.kind != ParamNode::Kind::kObject) return;
    for (const auto& p : schema["properties"].GetObject()) {
      const std::string key = p.name.GetString();
      const std::string at = path.empty() ? key : path + "." + key;
      const ParamNode* in_file = raw ? Member(*raw, key) : nullptr;
      const ParamNode* now = Member(loaded, key);
      if (p.value.IsObject() && p.value.HasMember("default") && !in_file) {
        ASSERT_NE(now, nullptr) << who << ": '" << at << "' left out and not given its schema default";
        EXPECT_TRUE(SameValue(*now, p.value["default"])) << who << ": '" << at << "' is not its schema default";
        ++defaults;
      } else if (in_file) {
        ASSERT_NE(now, nullptr) << who << ": '" << at << "' written in the file but gone";
        ++written;
      }
      if (now) Check(*now, in_file, p.value, at);
    }
  }
};

struct Plugins {
  std::ostringstream text;
  StreamLog log{text, LogLevel::kWarning};
  PluginRegistry registry{{UBERSIM_PLUGIN_BUILD_DIR}};
  ModelLoader loader{ModelLoader::DefaultSchemaDir(),
                     [this](PluginKind k, const std::string& id) { return registry.Find(k, id).schema_json; }};

  rapidjson::Document Schema(PluginKind kind, const std::string& id) {
    rapidjson::Document d;
    d.Parse(registry.Find(kind, id).schema_json.c_str());
    EXPECT_FALSE(d.HasParseError()) << id;
    return d;
  }
};

std::vector<fs::path> Files(const char* folder) {
  std::vector<fs::path> out;
  for (const auto& e : fs::directory_iterator(fs::path(UBERSIM_SOURCE_DIR "/models") / folder)) {
    if (e.path().extension() == ".yaml") out.push_back(e.path());
  }
  return out;
}

TEST(SchemaDefaults, EveryShippedRobotsPluginsGetTheirSchemaDefaults) {
  Plugins s;
  int defaults = 0, written = 0;
  for (const fs::path& file : Files("robots")) {
    const auto robot = s.loader.LoadRobot(file);
    const auto raw = ParseYamlFile(file);
    const std::pair<const char*, const std::optional<ComponentModel>*> parts[] = {
        {"drive", &robot->drive}, {"dribbler", &robot->dribbler}, {"kicker", &robot->kicker}};
    const PluginKind kinds[] = {PluginKind::kDrive, PluginKind::kDribbler, PluginKind::kKicker};
    for (int i = 0; i < 3; ++i) {
      if (!*parts[i].second) continue;
      const ComponentModel& c = **parts[i].second;
      Checker check{std::string(parts[i].first) + " '" + c.plugin + "' in " + file.filename().string()};
      check.Check(c.params.Node(), Member(*raw, parts[i].first), s.Schema(kinds[i], c.plugin), "");
      defaults += check.defaults;
      written += check.written;
    }
  }
  EXPECT_GE(defaults, 10) << "keys left out that the schemas give defaults";
  EXPECT_GE(written, 50) << "keys the robot files write";
}

TEST(SchemaDefaults, EveryShippedWorldsTransportsGetTheirSchemaDefaults) {
  Plugins s;
  int defaults = 0;
  for (const fs::path& file : Files("worlds")) {
    const WorldModel world = s.loader.LoadWorld(file);
    const auto raw = ParseYamlFile(file);
    const ParamNode* blocks = Member(*raw, "transports");
    ASSERT_NE(blocks, nullptr) << file;
    ASSERT_EQ(blocks->items.size(), world.transports.size()) << file;
    for (std::size_t i = 0; i < world.transports.size(); ++i) {
      const TransportModel& t = world.transports[i];
      Checker check{"transport '" + t.plugin + "' in " + file.filename().string()};
      check.Check(t.params.Node(), &blocks->items[i], s.Schema(PluginKind::kTransport, t.plugin), "");
      defaults += check.defaults;
    }
  }
  EXPECT_GE(defaults, 20) << "keys left out that the transport schemas give defaults";
}

}  // namespace
}  // namespace ubersim::kernel
