// SPDX-License-Identifier: Apache-2.0
#include "run_overrides.hpp"

#include <algorithm>
#include <cmath>

#include "ubersim/kernel/data_paths.hpp"
#include "ubersim/kernel/model.hpp"

namespace ubersim::kernel {
namespace {

using detail::ParamNode;

// Which transport parameter each port flag sets.
struct PortFlag {
  const char* flag;
  const char* plugin;
  const char* key;
};
constexpr PortFlag kPortFlags[] = {
    {"vision", "ssl_vision", "port"},       {"control", "ssl_simulation", "control_port"},
    {"blue", "ssl_simulation", "blue_port"}, {"yellow", "ssl_simulation", "yellow_port"},
    {"grsim", "grsim", "port"},             {"viewer", "viewer", "port"},
};

// Sets `key` of every `plugin` transport's block, then checks the block against the plugin's schema.
void SetTransportParam(WorldModel& world, PluginRegistry& registry, const std::string& flag, const std::string& plugin,
                       const std::string& key, ParamNode value) {
  bool found = false;
  for (TransportModel& t : world.transports) {
    if (t.plugin != plugin) continue;
    found = true;
    ParamNode block = t.params.Node();
    if (block.kind != ParamNode::Kind::kObject) block.kind = ParamNode::Kind::kObject;
    value.file = "--" + flag;
    const auto it = std::find_if(block.members.begin(), block.members.end(), [&](const auto& m) { return m.key == key; });
    if (it != block.members.end()) {
      it->value = value;
    } else {
      block.members.push_back(ParamNode::Member{key, value});
    }
    t.params = ParamView(std::make_shared<const ParamNode>(std::move(block)), t.params.Path());
    ValidateAgainstSchema(t.params, registry.Find(PluginKind::kTransport, plugin).schema_json,
                          "the schema of transport plugin '" + plugin + "'");
  }
  if (!found) {
    throw OverrideError("--" + flag + ": the world '" + world.name + "' starts no " + plugin + " transport");
  }
}

ParamNode Integer(std::int64_t v) {
  ParamNode n;
  n.kind = ParamNode::Kind::kInt;
  n.integer = v;
  n.number = static_cast<double>(v);
  return n;
}

ParamNode Text(const std::string& v) {
  ParamNode n;
  n.kind = ParamNode::Kind::kString;
  n.text = v;
  return n;
}

// ER-Force's geometry names for the league's fields.
std::string FieldName(const std::string& name) {
  if (name == "2020" || name == "2023" || name == "2023A") return "div-a";
  if (name == "2023B") return "div-b";
  return name;
}

void UseField(const std::string& asked, WorldModel& world, const ModelLoader& loader) {
  const std::string name = FieldName(asked);
  std::shared_ptr<const FieldModel> field;
  for (const auto& f : world.other_fields) {
    if (f->geometry.name == name) field = f;
  }
  if (world.field->geometry.name == name) field = world.field;
  if (!field) {
    const std::filesystem::path file = DataDir() / "models" / "fields" / (name + ".yaml");
    if (!std::filesystem::exists(file)) {
      std::string known = world.field->geometry.name;
      for (const auto& f : world.other_fields) known += ", " + f->geometry.name;
      throw OverrideError("--field " + asked + ": no field of that name (this world knows " + known + "; nor is there " +
                          file.string() + ")");
    }
    field = loader.LoadField(file);
    world.other_fields.push_back(field);
  }
  if (field == world.field) return;
  // The formation scales with the field, so every robot starts inside the new walls.
  const FieldGeometry& from = world.field->geometry;
  const FieldGeometry& to = field->geometry;
  const double sx = to.field_length / from.field_length, sy = to.field_width / from.field_width;
  for (RobotPlacement& p : world.robots) {
    p.x *= sx;
    p.y *= sy;
  }
  world.ball_start.x() *= sx;
  world.ball_start.y() *= sy;
  // As many cameras, as high, over the new carpet.
  world.perception.cameras = CamerasOver(world.perception.cameras, to);
  world.other_fields.push_back(world.field);  // a client may switch back
  world.field = field;
}

}  // namespace

std::vector<std::string> ApplyRunOverrides(const RunOverrides& o, WorldModel& world, const ModelLoader& loader,
                                           PluginRegistry& registry) {
  std::vector<std::string> notes;
  if (o.local_only) world.local_only = true;
  if (!o.field.empty()) UseField(o.field, world, loader);
  if (!o.realism.empty()) {
    PerceptionModel preset;
    RadioModel radio = world.radio;
    if (PerceptionPreset(o.realism, preset) && RadioPreset(o.realism, radio)) {
      // ÜberSim's own: its noise, drop-outs, latency and frame rate; the world's cameras stay.
      preset.cameras = world.perception.cameras;
      world.perception = preset;
    } else if (!LeagueRealismPreset(o.realism, world.perception, radio, world.held_ball)) {
      throw OverrideError("--realism " + o.realism + ": no such preset (ÜberSim's: ideal, 2003, realistic; the league's: " +
                          LeagueRealismPresetNames() + ")");
    }
    world.radio = radio;
  }
  for (const auto& entry : o.ports) {
    const std::string& flag = entry.first;
    const int port = entry.second;
    const auto it = std::find_if(std::begin(kPortFlags), std::end(kPortFlags),
                                 [&flag](const PortFlag& p) { return flag == p.flag; });
    if (it == std::end(kPortFlags)) throw OverrideError("unknown port flag --" + flag + "-port");
    SetTransportParam(world, registry, std::string(flag) + "-port", it->plugin, it->key, Integer(port));
  }
  if (!o.vision_address.empty()) {
    SetTransportParam(world, registry, "vision-address", "ssl_vision", "address", Text(o.vision_address));
  }
  const bool has_viewer = std::any_of(world.transports.begin(), world.transports.end(),
                                      [](const TransportModel& t) { return t.plugin == "viewer"; });
  if (o.viewer_referee_port && has_viewer) {
    SetTransportParam(world, registry, "referee-port", "viewer", "referee_port", Integer(*o.viewer_referee_port));
  }
  return notes;
}

}  // namespace ubersim::kernel
