// SPDX-License-Identifier: Apache-2.0
// ModelLoader: model files (world, field, ball, robot) -> validated, typed models.
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <system_error>
#include <utility>

#include "model_internal.hpp"
#include "robot_spec.hpp"
#include "model/urdf.hpp"
#include "ubersim/kernel/model.hpp"
#include "ubersim/kernel/plugin_registry.hpp"

namespace ubersim::kernel {
namespace {

namespace fs = std::filesystem;
using detail::ParamNode;
using model_detail::Describe;
using model_detail::ErrorAt;
using model_detail::FormatNumber;

// Every key of a `perception:` block `p` over `m` (a preset's values).
void ApplyPerceptionKeys(PerceptionModel& m, const ParamView& p, const FieldGeometry& field) {
  m.frame_rate = p.GetDouble("frame_rate", m.frame_rate);
  m.latency = p.GetDouble("latency", m.latency);
  if (p.Has("noise")) {
    const ParamView n = p["noise"];
    m.ball_position_sigma = n.GetDouble("ball_position", m.ball_position_sigma);
    m.robot_position_sigma = n.GetDouble("robot_position", m.robot_position_sigma);
    m.robot_orientation_sigma = n.GetDouble("robot_orientation", m.robot_orientation_sigma);
  }
  if (p.Has("drop")) {
    m.ball_drop = p["drop"].GetDouble("ball", m.ball_drop);
    m.robot_drop = p["drop"].GetDouble("robot", m.robot_drop);
  }
  m.camera_overlap = p.GetDouble("camera_overlap", m.camera_overlap);
  if (p.Has("occlusion")) {
    const ParamView o = p["occlusion"];
    m.ball_occlusion = o.GetBool("enabled", m.ball_occlusion);
    m.ball_visibility_threshold = o.GetDouble("visibility_threshold", m.ball_visibility_threshold);
  }
  if (p.Has("noise")) m.ball_area_sigma = p["noise"].GetDouble("ball_area", m.ball_area_sigma);
  m.dribbler_false_balls = p.GetDouble("dribbler_false_balls", m.dribbler_false_balls);
  m.camera_position_error = p.GetDouble("camera_position_error", m.camera_position_error);
  m.object_offset = p.GetDouble("object_offset", m.object_offset);
  if (p.Has("processing_time")) m.processing_time = p.GetDouble("processing_time", 0.0);
  m.unsynchronised_cameras = p.GetBool("unsynchronised_cameras", m.unsynchronised_cameras);
  m.capture_jitter = p.GetDouble("capture_jitter", m.capture_jitter);
  if (p.Has("noise")) m.noise_growth = p["noise"].GetDouble("growth_per_metre", m.noise_growth);
  m.exposure = p.GetDouble("exposure", m.exposure);
  if (!p.Has("cameras")) {
    m.cameras = CameraGrid(static_cast<int>(p.GetInt("camera_count", 1)), field.carpet_length,
                           field.carpet_width, p.GetDouble("camera_height", 6.0));
    return;
  }
  m.cameras.clear();
  const ParamView list = p["cameras"];
  std::map<int, int> ids;  // id -> line
  for (std::size_t i = 0; i < list.Size(); ++i) {
    const ParamView c = list.At(i);
    CameraModel cam;
    cam.id = static_cast<int>(c.GetInt("id", static_cast<std::int64_t>(i)));
    const ParamView pos = c["position"], area = c["area"];
    cam.position = Vec3(pos.At(0).AsDouble(), pos.At(1).AsDouble(), pos.At(2).AsDouble());
    cam.x_min = area.At(0).AsDouble();
    cam.y_min = area.At(1).AsDouble();
    cam.x_max = area.At(2).AsDouble();
    cam.y_max = area.At(3).AsDouble();
    if (cam.x_min >= cam.x_max || cam.y_min >= cam.y_max) {
      throw ErrorAt(area, "expected [x_min, y_min, x_max, y_max] with x_min < x_max and y_min < y_max");
    }
    if (cam.position.z() <= 0) throw ErrorAt(pos.At(2), "a camera hangs above the carpet: z must be > 0 m");
    const ParamView id_node = c.Has("id") ? c["id"] : c;
    if (const auto it = ids.find(cam.id); it != ids.end()) {
      throw ErrorAt(id_node, "camera id " + std::to_string(cam.id) + " is already used at line " +
                                 std::to_string(it->second));
    }
    ids[cam.id] = id_node.Node().line;
    m.cameras.push_back(cam);
  }
}

// Every key of a `radio:` block `r` over `m`.
void ApplyRadioKeys(RadioModel& m, const ParamView& r) {
  m.latency = r.GetDouble("latency", m.latency);
  m.loss = r.GetDouble("loss", m.loss);
  m.response_loss = r.GetDouble("response_loss", m.response_loss);
}

ParamView BlockOf(const ParamView& world, const char* key) {
  return world.Has(key) ? world[key] : ParamView::FromJson("{}");
}

// The `perception:` and `radio:` blocks: their presets' defaults, the league's `realism:` preset
// over them when the world names one, then every key given.
void LoadVisionAndRadio(const ParamView& world, WorldModel& w) {
  const ParamView p = BlockOf(world, "perception"), r = BlockOf(world, "radio");
  PerceptionPreset(p.GetString("preset", "ideal"), w.perception);  // the schema allows only known names
  RadioPreset(r.GetString("preset", "ideal"), w.radio);
  if (world.Has("realism")) {
    LeagueRealismPreset(world.GetString("realism", "None"), w.perception, w.radio, w.held_ball);
  }
  ApplyPerceptionKeys(w.perception, p, w.field->geometry);
  ApplyRadioKeys(w.radio, r);
  if (world.Has("dribbling")) w.held_ball = world.GetString("dribbling", "physical") == "held";
}

constexpr const char* kKinds[] = {"world", "field", "ball", "robot"};

std::string Metres(double v) { return FormatNumber(v) + " m"; }
std::string Kilograms(double v) { return FormatNumber(v) + " kg"; }

/// The `kind:` of a model file's root; throws ModelError when it is missing or unknown.
std::string KindOf(const ParamView& root) {
  if (root.IsNull()) {
    throw ErrorAt(root, "", "the file is empty (a model file starts with 'kind: world|field|ball|robot')");
  }
  if (!root.IsObject()) {
    throw ErrorAt(root, "", "expected a mapping of keys at the top level (a model file starts with "
                            "'kind: world|field|ball|robot'), got " + Describe(root.Node()));
  }
  if (!root.Has("kind")) {
    throw ErrorAt(root, "kind", "missing required key 'kind' (one of: world, field, ball, robot)");
  }
  const ParamView k = root["kind"];
  if (!k.IsString()) throw ErrorAt(k, "expected a string, got " + Describe(k.Node()));
  const std::string kind = k.AsString();
  for (const char* known : kKinds) {
    if (kind == known) return kind;
  }
  throw ErrorAt(k, "unknown kind '" + kind + "' (allowed: world, field, ball, robot)");
}

std::string ErrnoText(int err) { return std::strerror(err ? err : ENOENT); }

/// Why `file` cannot be read, or "" when it can.
std::string Unreadable(const fs::path& file) {
  std::error_code ec;
  if (fs::is_directory(file, ec)) return std::strerror(EISDIR);
  errno = 0;
  std::ifstream probe(file, std::ios::binary);
  if (!probe) return ErrnoText(errno);
  return "";
}

SurfaceMaterial ReadSurface(const ParamView& parent, const char* key, const std::string& default_name) {
  SurfaceMaterial s;
  s.name = default_name;
  if (!parent.Has(key)) return s;
  const ParamView v = parent[key];
  s.name = v.GetString("name", default_name);
  s.mu = v.GetDouble("mu", s.mu);
  s.mu2 = v.GetDouble("mu2", s.mu2);
  s.bounce = v.GetDouble("bounce", s.bounce);
  s.bounce_velocity = v.GetDouble("bounce_velocity", s.bounce_velocity);
  s.soft_erp = v.GetDouble("soft_erp", s.soft_erp);
  s.soft_cfm = v.GetDouble("soft_cfm", s.soft_cfm);
  s.rolling_friction = v.GetDouble("rolling_friction", s.rolling_friction);
  s.slip = v.GetDouble("slip", s.slip);
  return s;
}

/// A copy of the object `block` without its `plugin` member: the plugin's own parameters.
std::shared_ptr<const ParamNode> WithoutPlugin(const ParamView& block) {
  auto copy = std::make_shared<ParamNode>(block.Node());
  auto& m = copy->members;
  for (auto it = m.begin(); it != m.end(); ++it) {
    if (it->key == "plugin") {
      m.erase(it);
      break;
    }
  }
  return copy;
}

}  // namespace

struct ModelLoader::Impl {
  fs::path schema_dir;
  PluginSchemaLookup lookup;
  mutable std::mutex mutex;
  mutable std::map<std::string, std::string> schemas;

  const std::string& Schema(const std::string& kind) const {
    std::lock_guard<std::mutex> lock(mutex);
    auto it = schemas.find(kind);
    if (it != schemas.end()) return it->second;
    const fs::path p = schema_dir / (kind + ".schema.json");
    errno = 0;
    std::ifstream in(p, std::ios::binary);
    if (!in) {
      throw ModelError(p.string(), 0, 0, "",
                       "cannot open file: " + ErrnoText(errno) +
                           " (the schemas folder; set UBERSIM_SCHEMA_DIR to override)");
    }
    std::ostringstream text;
    text << in.rdbuf();
    return schemas.emplace(kind, text.str()).first->second;
  }

  /// Reads `file`, checks it is a `kind` model and validates it against the kind's schema.
  /// `naming` is the key of another file that names this one (errors about opening the file or
  /// its kind are reported there), or nullptr.
  ParamView Read(const fs::path& file, const std::string& kind, const ParamView* naming) const {
    if (naming) {
      if (const std::string why = Unreadable(file); !why.empty()) {
        throw ErrorAt(*naming, "cannot open " + kind + " file '" + file.string() + "': " + why);
      }
    }
    return Checked(ParamView(ParseYamlFile(file)), kind, naming, file);
  }

  /// Checks that the parsed `root` of `file` is a `kind` model and validates it against the
  /// kind's schema (`naming` as for Read).
  ParamView Checked(const ParamView& root, const std::string& kind, const ParamView* naming,
                    const fs::path& file) const {
    const std::string actual = KindOf(root);
    if (actual != kind) {
      if (naming) {
        throw ErrorAt(*naming, "'" + file.string() + "' is a " + actual + " model (kind: " + actual +
                                   "), expected a " + kind + " model");
      }
      throw ErrorAt(root["kind"], "expected kind '" + kind + "', got '" + actual + "'");
    }
    ValidateAgainstSchema(root, Schema(kind), kind + ".schema.json");
    return root;
  }

  /// Checks a plugin's parameter block against the schema the plugin ships.
  /// `params` checked against plugin `id`'s schema, with the schema's defaults filled in (the
  /// defaults in force are the ones the schema documents).
  ParamView CheckPlugin(PluginKind kind, const std::string& id, const ParamView& plugin_key,
                        const ParamView& params) const {
    if (!lookup) return params;
    std::string schema;
    try {
      schema = lookup(kind, id);
    } catch (const std::exception& e) {
      // Refused is not unknown: a team with a stale library must read why it was refused.
      const auto* load = dynamic_cast<const PluginLoadError*>(&e);
      const std::string what = load && !load->not_found() ? "plugin '" + id + "' is refused: " + load->reason()
                                                          : "unknown plugin '" + id + "': " + e.what();
      const ModelError located = ErrorAt(plugin_key, what);
      throw PluginLookupError(located.file(), located.line(), located.column(), located.key(), located.reason());
    }
    if (schema.empty()) return params;  // the plugin declares no schema: nothing to check
    const std::string label = "the schema of " + std::string(ToString(kind)) + " plugin '" + id + "'";
    try {
      ValidateAgainstSchema(params, schema, label);
    } catch (const ModelError& e) {
      // A team's first schema often lists `plugin` as required; the model file has it, so saying
      // it is missing would send them looking in the wrong file.
      if (e.reason().find("missing required key 'plugin'") == std::string::npos) throw;
      throw ErrorAt(plugin_key, label + " requires a 'plugin' key, but `plugin:` names the plugin and is taken "
                                        "out of the block before its schema sees it: remove \"plugin\" from the "
                                        "schema's \"required\" (docs/plugins.md, Parameters)");
    }
    return WithSchemaDefaults(params, schema, label);
  }

  /// The component block `key` of a robot (drive, dribbler, kicker), if present.
  std::optional<ComponentModel> Component(const ParamView& root, const char* key,
                                          PluginKind kind) const {
    if (!root.Has(key)) return std::nullopt;
    const ParamView block = root[key];
    const ParamView plugin_key = block["plugin"];
    ComponentModel c;
    c.plugin = plugin_key.AsString();
    c.params = CheckPlugin(kind, c.plugin, plugin_key, ParamView(WithoutPlugin(block), block.Path()));
    return c;
  }

  std::shared_ptr<const FieldModel> Field(const fs::path& file, const ParamView* naming) const {
    return FieldFrom(file, Read(file, "field", naming));
  }

  /// The field of the checked root `v` of `file` (the same split for the other kinds).
  std::shared_ptr<const FieldModel> FieldFrom(const fs::path& file, const ParamView& v) const {
    auto f = std::make_shared<FieldModel>();
    f->file = file.string();
    FieldGeometry& g = f->geometry;
    g.name = v["name"].AsString();
    g.field_length = v["field_length"].AsDouble();
    g.field_width = v["field_width"].AsDouble();
    g.boundary_width = v["boundary_width"].AsDouble();
    const double goal_line_boundary = v.GetDouble("goal_line_boundary_width", g.boundary_width);
    g.line_thickness = v.GetDouble("line_thickness", 0.01);
    g.center_circle_radius = v.GetDouble("center_circle_radius", 0.0);
    if (v.Has("penalty_area")) {
      g.penalty_area_depth = v["penalty_area"]["depth"].AsDouble();
      g.penalty_area_width = v["penalty_area"]["width"].AsDouble();
    }
    g.goal_center_to_penalty_mark = v.GetDouble("penalty_mark_distance", 0.0);
    const ParamView goal = v["goal"];
    g.goal_width = goal["width"].AsDouble();
    g.goal_depth = goal["depth"].AsDouble();
    g.goal_height = goal["height"].AsDouble();
    f->goal_wall_thickness = goal.GetDouble("wall_thickness", f->goal_wall_thickness);
    if (v.Has("wall")) {
      const ParamView wall = v["wall"];
      f->wall.height = wall.GetDouble("height", f->wall.height);
      f->wall.thickness = wall.GetDouble("thickness", f->wall.thickness);
      f->wall.corner_cut = wall.GetDouble("corner_cut", f->wall.corner_cut);
    }
    g.carpet_length = g.field_length + 2.0 * goal_line_boundary;
    g.carpet_width = g.field_width + 2.0 * g.boundary_width;
    const ParamView surfaces = v.Has("surfaces") ? v["surfaces"] : ParamView();
    f->carpet = ReadSurface(surfaces, "carpet", "carpet");
    f->wall_surface = ReadSurface(surfaces, "wall", "wall");
    f->goal_surface = ReadSurface(surfaces, "goal", "goal");

    // Sizes that each pass the schema but do not fit together.
    if (g.goal_width >= g.field_width) {
      throw ErrorAt(goal["width"], "the goal (" + Metres(g.goal_width) +
                                       ") must be narrower than the field (" + Metres(g.field_width) + ")");
    }
    if (v.Has("penalty_area")) {
      const ParamView pa = v["penalty_area"];
      if (g.penalty_area_width >= g.field_width) {
        throw ErrorAt(pa["width"], "the defense area (" + Metres(g.penalty_area_width) +
                                       ") must be narrower than the field (" + Metres(g.field_width) + ")");
      }
      if (g.penalty_area_depth >= 0.5 * g.field_length) {
        throw ErrorAt(pa["depth"], "the defense area depth (" + Metres(g.penalty_area_depth) +
                                       ") must be less than half the field length (" +
                                       Metres(0.5 * g.field_length) + ")");
      }
    }
    if (g.center_circle_radius >= 0.5 * std::min(g.field_length, g.field_width)) {
      throw ErrorAt(v["center_circle_radius"], "the centre circle (radius " +
                                                   Metres(g.center_circle_radius) +
                                                   ") does not fit on the field");
    }
    if (g.goal_center_to_penalty_mark >= g.field_length) {
      throw ErrorAt(v["penalty_mark_distance"], "the penalty mark (" +
                                                    Metres(g.goal_center_to_penalty_mark) +
                                                    " from the goal) lies beyond the field length (" +
                                                    Metres(g.field_length) + ")");
    }
    if (f->wall.corner_cut >= 0.5 * std::min(g.carpet_length, g.carpet_width)) {
      throw ErrorAt(v["wall"]["corner_cut"], "the corner cut (" + Metres(f->wall.corner_cut) +
                                                 ") must be less than half the walled width (" +
                                                 Metres(0.5 * std::min(g.carpet_length, g.carpet_width)) + ")");
    }
    BuildFieldMarkings(g);
    return f;
  }

  std::shared_ptr<const BallModel> Ball(const fs::path& file, const ParamView* naming) const {
    return BallFrom(file, Read(file, "ball", naming));
  }

  std::shared_ptr<const BallModel> BallFrom(const fs::path& file, const ParamView& v) const {
    auto b = std::make_shared<BallModel>();
    b->file = file.string();
    b->name = v["name"].AsString();
    b->radius = v["radius"].AsDouble();
    b->mass = v["mass"].AsDouble();
    b->inertia_factor = v.GetDouble("inertia_factor", b->inertia_factor);
    if (v.Has("damping")) {
      b->linear_damping = v["damping"].GetDouble("linear", b->linear_damping);
      b->angular_damping = v["damping"].GetDouble("angular", b->angular_damping);
    }
    b->surface = ReadSurface(v, "surface", "ball");
    return b;
  }

  std::shared_ptr<const RobotModel> Robot(const fs::path& file, const ParamView* naming) const {
    return RobotFrom(file, Read(file, "robot", naming));
  }

  std::shared_ptr<const RobotModel> RobotFrom(const fs::path& file, const ParamView& v) const {
    auto r = std::make_shared<RobotModel>();
    r->file = file.string();
    r->name = v["name"].AsString();
    const ParamView body = v["body"];
    r->body.mass = body["mass"].AsDouble();
    r->body.radius = body["radius"].AsDouble();
    r->body.height = body["height"].AsDouble();
    r->body.front_distance = body.GetDouble("front_distance", r->body.radius);
    r->body.ground_clearance = body.GetDouble("ground_clearance", r->body.ground_clearance);
    r->body.center_of_mass_height = body.GetDouble("center_of_mass_height", r->body.center_of_mass_height);
    if (body.Has("center_of_mass_height") &&
        (r->body.center_of_mass_height > body.GetDouble("height", 0.0))) {
      throw ErrorAt(body["center_of_mass_height"], "the centre of mass (" +
                                                       Metres(r->body.center_of_mass_height) +
                                                       ") must not be above the robot's height");
    }
    if (r->body.front_distance > r->body.radius) {
      throw ErrorAt(body["front_distance"], "the flat front (" + Metres(r->body.front_distance) +
                                                " from the centre) lies outside the radius (" +
                                                Metres(r->body.radius) + ")");
    }
    if (r->body.ground_clearance >= r->body.height) {
      throw ErrorAt(body["ground_clearance"], "the ground clearance (" +
                                                  Metres(r->body.ground_clearance) +
                                                  ") must be less than the height (" +
                                                  Metres(r->body.height) + ")");
    }
    if (v.Has("urdf")) {
      fs::path urdf = v["urdf"].AsString();
      if (urdf.is_relative()) urdf = file.parent_path() / urdf;
      if (const std::string why = Unreadable(urdf); !why.empty()) {
        throw ErrorAt(v["urdf"], "cannot open URDF file " + urdf.string() + ": " + why);
      }
      r->urdf_file = urdf.lexically_normal().string();
      // Read now, not only when a robot is built, so that `ubersim validate` refuses what
      // `ubersim run` would: XML, links, masses, meshes, joints, and the root link's mass.
      const UrdfRobot parsed = LoadUrdf(r->urdf_file);
      const UrdfLink& root = parsed.links.front();
      if (std::abs(root.mass.mass - r->body.mass) > 0.01 * r->body.mass) {
        throw ErrorAt(body["mass"], "body.mass " + Kilograms(r->body.mass) + " differs from the URDF root link '" +
                                        root.name + "' mass " + Kilograms(root.mass.mass) + " (" + parsed.file + ")");
      }
    }
    r->min_solver_iterations = static_cast<int>(v.GetInt("min_solver_iterations", 0));
    if (v.Has("dribbling")) r->held_ball = v.GetString("dribbling", "physical") == "held";
    r->source = v;
    r->surface = ReadSurface(v, "surface", "robot");
    r->drive = Component(v, "drive", PluginKind::kDrive);
    r->dribbler = Component(v, "dribbler", PluginKind::kDribbler);
    r->kicker = Component(v, "kicker", PluginKind::kKicker);
    return r;
  }

  WorldModel World(const fs::path& file) const { return WorldFrom(file, Read(file, "world", nullptr)); }

  WorldModel WorldFrom(const fs::path& file, const ParamView& v) const {
    WorldModel w;
    w.file = file.string();
    w.name = v["name"].AsString();
    const fs::path base = file.parent_path();
    const auto resolve = [&](const ParamView& key) {
      fs::path p = key.AsString();
      if (p.is_relative()) p = base / p;
      return p.lexically_normal();
    };

    const ParamView field_key = v["field"];
    w.field = Field(resolve(field_key), &field_key);
    if (v.Has("fields")) {
      const ParamView fields = v["fields"];
      for (std::size_t i = 0; i < fields.Size(); ++i) {
        const ParamView key = fields.At(i);
        const fs::path file = resolve(key);
        if (file.string() == w.field->file) continue;  // the world's own
        auto other = Field(file, &key);
        for (const auto& known : w.other_fields) {
          if (known->geometry.name == other->geometry.name) {
            throw ErrorAt(key, "a field named '" + other->geometry.name + "' is listed already");
          }
        }
        w.other_fields.push_back(std::move(other));
      }
    }
    const ParamView ball_key = v["ball"];
    w.ball = Ball(resolve(ball_key), &ball_key);
    const FieldGeometry& g = w.field->geometry;
    const double half_x = 0.5 * g.carpet_length, half_y = 0.5 * g.carpet_width;

    if (v.Has("ball_start")) {
      const ParamView bs = v["ball_start"];
      w.ball_start = bs.AsVec3();
      const double reach_x = std::max(half_x, 0.5 * g.field_length + g.goal_depth);
      if (std::abs(w.ball_start.x()) > reach_x || std::abs(w.ball_start.y()) > half_y) {
        throw ErrorAt(bs, "the ball start (" + FormatNumber(w.ball_start.x()) + ", " +
                              FormatNumber(w.ball_start.y()) + ") lies outside the walls of field '" +
                              g.name + "' (|x| ≤ " + Metres(reach_x) + ", |y| ≤ " + Metres(half_y) + ")");
      }
    }

    if (v.Has("robots")) {
      const ParamView robots = v["robots"];
      std::map<std::string, std::shared_ptr<const RobotModel>> models;
      std::map<std::pair<int, int>, int> placed;  // (team, id) -> line
      for (std::size_t i = 0; i < robots.Size(); ++i) {
        const ParamView e = robots.At(i);
        RobotPlacement p;
        p.id.team = e["team"].AsString() == "yellow" ? Team::kYellow : Team::kBlue;
        p.id.id = static_cast<int>(e["id"].AsInt());
        const ParamView model_key = e["model"];
        const fs::path model_file = resolve(model_key);
        auto& model = models[model_file.string()];
        if (!model) model = Robot(model_file, &model_key);
        p.model = model;
        p.x = e.GetDouble("x", 0.0);
        p.y = e.GetDouble("y", 0.0);
        p.yaw = e.GetDouble("yaw", 0.0);
        p.present = e.GetBool("present", true);
        const auto key = std::make_pair(static_cast<int>(p.id.team), p.id.id);
        if (const auto it = placed.find(key); it != placed.end()) {
          throw ErrorAt(e["id"], "robot " + ToString(p.id) + " is already placed at line " +
                                     std::to_string(it->second));
        }
        placed[key] = e.Node().line;
        if (std::abs(p.x) > half_x) {
          throw ErrorAt(e["x"], "x " + Metres(p.x) + " lies outside the walls (|x| ≤ " + Metres(half_x) + ")");
        }
        if (std::abs(p.y) > half_y) {
          throw ErrorAt(e["y"], "y " + Metres(p.y) + " lies outside the walls (|y| ≤ " + Metres(half_y) + ")");
        }
        w.robots.push_back(std::move(p));
      }
    }

    // Each team's model for robots that come on while the world runs.
    for (Team team : {Team::kBlue, Team::kYellow}) {
      auto& model = w.team_models[team == Team::kBlue ? 0 : 1];
      const char* name = ToString(team);
      if (v.Has("teams") && v["teams"].Has(name)) {
        const ParamView key = v["teams"][name]["model"];
        model = Robot(resolve(key), &key);
      }
      for (const RobotPlacement& p : w.robots) {
        if (!model && p.id.team == team) model = p.model;
      }
    }
    for (int t = 0; t < 2; ++t) {
      if (!w.team_models[t]) w.team_models[t] = w.team_models[1 - t];
    }

    if (v.Has("physics")) {
      // The profile first, then the keys the file sets over it (kept, so that another profile
      // chosen on the command line still gets them).
      const ParamView p = v["physics"];
      PhysicsOverrides keys;
      if (p.Has("step")) keys.step = p["step"].AsDouble();
      if (p.Has("solver_iterations")) keys.solver_iterations = static_cast<int>(p["solver_iterations"].AsInt());
      if (p.Has("solver_iterations_without_ball")) {
        keys.solver_iterations_without_ball = static_cast<int>(p["solver_iterations_without_ball"].AsInt());
      }
      if (p.Has("erp")) keys.erp = p["erp"].AsDouble();
      if (p.Has("cfm")) keys.cfm = p["cfm"].AsDouble();
      if (p.Has("gravity")) keys.gravity = p["gravity"].AsVec3();
      if (p.Has("broadphase")) keys.broadphase = p["broadphase"].AsString();
      if (p.Has("max_contacts")) keys.max_contacts = static_cast<int>(p["max_contacts"].AsInt());
      if (p.Has("contact_surface_layer")) keys.contact_surface_layer = p["contact_surface_layer"].AsDouble();
      if (p.Has("contact_max_correcting_velocity")) {
        keys.contact_max_correcting_velocity = p["contact_max_correcting_velocity"].AsDouble();
      }
      if (p.Has("speculative_robot_contacts")) keys.speculative_robot_contacts = p["speculative_robot_contacts"].AsBool();
      if (p.Has("robot_contact_erp")) keys.robot_contact_erp = p["robot_contact_erp"].AsDouble();
      const std::string profile = p.GetString("profile", w.physics.profile);
      if (!PhysicsProfile(profile, w.physics)) {  // the schema's enum lists them: kept in step by a test
        throw ErrorAt(p["profile"], "unknown physics profile '" + profile + "'");
      }
      keys.ApplyTo(w.physics);
      w.physics.world_keys = keys;
    }
    w.seed = static_cast<std::uint64_t>(v.GetInt("seed", static_cast<std::int64_t>(w.seed)));
    w.on_plugin_fault = v.GetString("on_plugin_fault", w.on_plugin_fault);
    w.local_only = v.GetBool("local_only", w.local_only);
    if (v.Has("match")) w.match = v["match"];

    if (v.Has("plugin_paths")) {
      const ParamView paths = v["plugin_paths"];
      for (std::size_t i = 0; i < paths.Size(); ++i) w.plugin_paths.push_back(resolve(paths.At(i)));
    }

    if (v.Has("transports")) {
      const ParamView transports = v["transports"];
      for (std::size_t i = 0; i < transports.Size(); ++i) {
        const ParamView block = transports.At(i);
        const ParamView plugin_key = block["plugin"];
        TransportModel t;
        t.plugin = plugin_key.AsString();
        t.params = CheckPlugin(PluginKind::kTransport, t.plugin, plugin_key, ParamView(WithoutPlugin(block), block.Path()));
        w.transports.push_back(std::move(t));
      }
    }

    if (v.Has("materials")) {
      const ParamView materials = v["materials"];
      std::map<std::pair<std::string, std::string>, int> seen;  // sorted pair -> line
      for (std::size_t i = 0; i < materials.Size(); ++i) {
        const ParamView e = materials.At(i);
        const ParamView between = e["between"];
        MaterialPair m;
        m.a = between.At(0).AsString();
        m.b = between.At(1).AsString();
        SurfaceMaterial s;
        s.name = m.a + "|" + m.b;
        s.mu = e.GetDouble("mu", s.mu);
        s.mu2 = e.GetDouble("mu2", s.mu2);
        s.bounce = e.GetDouble("bounce", s.bounce);
        s.bounce_velocity = e.GetDouble("bounce_velocity", s.bounce_velocity);
        s.soft_erp = e.GetDouble("soft_erp", s.soft_erp);
        s.soft_cfm = e.GetDouble("soft_cfm", s.soft_cfm);
        s.rolling_friction = e.GetDouble("rolling_friction", s.rolling_friction);
        s.slip = e.GetDouble("slip", s.slip);
        m.surface = s;
        const auto key = m.a < m.b ? std::make_pair(m.a, m.b) : std::make_pair(m.b, m.a);
        if (const auto it = seen.find(key); it != seen.end()) {
          throw ErrorAt(between, "the pair " + m.a + "|" + m.b + " is already given at line " +
                                     std::to_string(it->second));
        }
        seen[key] = between.Node().line;
        w.material_pairs.push_back(std::move(m));
      }
    }

    LoadVisionAndRadio(v, w);
    return w;
  }
};

namespace {

/// Runs `f`; a ParamError (a getter on a value the schema let through in an unexpected shape,
/// e.g. with an edited schema) becomes a ModelError of `file`.
template <typename F>
auto Guard(const fs::path& file, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const ParamError& e) {
    throw ModelError(file.string(), 0, 0, "", e.what());
  }
}

}  // namespace

ModelLoader::ModelLoader(std::filesystem::path schema_dir, PluginSchemaLookup plugin_schema) {
  auto impl = std::make_shared<Impl>();
  impl->schema_dir = std::move(schema_dir);
  impl->lookup = std::move(plugin_schema);
  impl_ = std::move(impl);
}

WorldModel ModelLoader::LoadWorld(const std::filesystem::path& file) const {
  return Guard(file, [&] { return impl_->World(file); });
}

std::shared_ptr<const FieldModel> ModelLoader::LoadField(const std::filesystem::path& file) const {
  return Guard(file, [&] { return impl_->Field(file, nullptr); });
}

std::shared_ptr<const BallModel> ModelLoader::LoadBall(const std::filesystem::path& file) const {
  return Guard(file, [&] { return impl_->Ball(file, nullptr); });
}

std::shared_ptr<const RobotModel> ModelLoader::LoadRobot(const std::filesystem::path& file) const {
  return Guard(file, [&] { return impl_->Robot(file, nullptr); });
}

SpecOutcome ModelLoader::ApplySpec(const RobotModel& base, const RobotSpec& spec) const {
  using model_detail::SpecEdit;
  SpecOutcome out;
  const std::string source = "robot_specs";
  const ParamNode& root = base.source.Node();
  // Where each set field goes.
  std::vector<std::pair<std::string, std::vector<SpecEdit>>> fields;
  const std::pair<const char*, const char*> body_keys[] = {
      {"radius", "radius"}, {"height", "height"}, {"mass", "mass"}, {"center_to_dribbler", "front_distance"}};
  const std::pair<const char*, const std::optional<ComponentModel>*> parts[] = {
      {"drive", &base.drive}, {"dribbler", &base.dribbler}, {"kicker", &base.kicker}};
  const PluginKind kinds[] = {PluginKind::kDrive, PluginKind::kDribbler, PluginKind::kKicker};
  for (const std::string& field : model_detail::SetFields(spec)) {
    std::vector<SpecEdit> edits;
    bool placed = false;
    for (const auto& [name, key] : body_keys) {
      if (field != name) continue;
      placed = true;
      if (!base.urdf_file.empty() && field != "center_to_dribbler") {
        out.unmapped.push_back(field + " (the body comes from the URDF " + base.urdf_file + ")");
      } else {
        edits.push_back(SpecEdit{field, {"body", key}, std::nullopt, "", *model_detail::ScalarField(spec, field)});
      }
    }
    for (std::size_t k = 0; k < 3 && !placed; ++k) {
      const std::optional<ComponentModel>& c = *parts[k].second;
      if (!c || !impl_->lookup) continue;
      std::string schema;
      try {
        schema = impl_->lookup(kinds[k], c->plugin);
      } catch (const std::exception&) {
        continue;  // the model named a plugin that is gone: it was refused when loaded
      }
      for (const model_detail::SpecTarget& t : model_detail::SpecTargets(schema)) {
        if (t.field != field) continue;
        std::vector<std::string> path = {parts[k].first};
        path.insert(path.end(), t.path.begin(), t.path.end());
        if (field != "wheel_angles") {
          edits.push_back(SpecEdit{field, path, std::nullopt, "", *model_detail::ScalarField(spec, field) * t.scale});
          continue;
        }
        const ParamView array = [&] {
          ParamView v = base.source;
          for (const std::string& key : path) v = v[key];
          return v;
        }();
        if (array.Size() != spec.wheel_angles->size()) {
          out.errors.push_back(model_detail::DescribeField(spec, field) + ": " + std::to_string(spec.wheel_angles->size()) +
                               " angles for a drive with " + std::to_string(array.Size()) + " wheels");
          placed = true;
          edits.clear();
          break;
        }
        for (std::size_t i = 0; i < array.Size(); ++i) {
          edits.push_back(SpecEdit{field, path, i, t.member, (*spec.wheel_angles)[i] * t.scale});
        }
      }
    }
    if (!edits.empty()) {
      fields.emplace_back(field, std::move(edits));
    } else if (!placed) {
      out.unmapped.push_back(field + " (robot model '" + base.name + "' has no place for it)");
    }
  }
  if (!out.errors.empty()) return out;

  const auto build = [&](const std::vector<SpecEdit>& edits) {
    ParamNode edited = root;
    for (const SpecEdit& e : edits) edited = model_detail::WithEdit(edited, e, source);
    const ParamView view(std::make_shared<const ParamNode>(std::move(edited)));
    return impl_->RobotFrom(base.file, impl_->Checked(view, "robot", nullptr, base.file));
  };
  // Each value alone first: one error per value the model refuses.
  std::vector<SpecEdit> all;
  for (const auto& [field, edits] : fields) {
    try {
      build(edits);
    } catch (const ModelError& e) {
      out.errors.push_back(model_detail::DescribeField(spec, field) + ": " +
                           (e.key().empty() ? std::string() : "key '" + e.key() + "': ") + e.reason());
    }
    all.insert(all.end(), edits.begin(), edits.end());
  }
  if (!out.errors.empty()) return out;
  try {
    auto model = std::const_pointer_cast<RobotModel>(build(all));
    char digest[17];
    std::snprintf(digest, sizeof digest, "%016llx", static_cast<unsigned long long>(model_detail::SpecDigest(spec)));
    model->name = base.name + " (robot_specs " + digest + ")";
    out.model = std::move(model);
  } catch (const ModelError& e) {
    out.errors.push_back("the values together: " + (e.key().empty() ? std::string() : "key '" + e.key() + "': ") +
                         e.reason());
  }
  return out;
}

std::string ModelLoader::Validate(const std::filesystem::path& file) const {
  const std::string kind = KindOf(ParamView(ParseYamlFile(file)));
  if (kind == "world") LoadWorld(file);
  else if (kind == "field") LoadField(file);
  else if (kind == "ball") LoadBall(file);
  else LoadRobot(file);
  return kind;
}

std::string ModelLoader::ValidateText(const std::string& text, const std::filesystem::path& file) const {
  const ParamView root(ParseYamlText(text, file.string()));
  const std::string kind = KindOf(root);
  Guard(file, [&] {
    const ParamView v = impl_->Checked(root, kind, nullptr, file);
    if (kind == "world") impl_->WorldFrom(file, v);
    else if (kind == "field") impl_->FieldFrom(file, v);
    else if (kind == "ball") impl_->BallFrom(file, v);
    else impl_->RobotFrom(file, v);
  });
  return kind;
}

std::filesystem::path ModelLoader::DefaultSchemaDir() {
  if (const char* env = std::getenv("UBERSIM_SCHEMA_DIR"); env && *env) return fs::path(env);
  std::vector<fs::path> candidates;
  if (const char* data = std::getenv("UBERSIM_DATA_DIR"); data && *data) {
    candidates.push_back(fs::path(data) / "schemas");
  }
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) candidates.push_back(exe.parent_path() / ".." / UBERSIM_DATA_INSTALL_DIR / "schemas");
  candidates.push_back(fs::path(UBERSIM_SOURCE_DIR) / "schemas");
  for (const fs::path& c : candidates) {
    if (fs::is_directory(c, ec)) {
      const fs::path canonical = fs::weakly_canonical(c, ec);
      return ec ? c : canonical;
    }
  }
  return candidates.back();
}

}  // namespace ubersim::kernel
