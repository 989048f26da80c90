// SPDX-License-Identifier: Apache-2.0
// ModelLoader: the shipped model files, typed values, and every kind of error with its location.
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "test_files.hpp"
#include "ubersim/kernel/model.hpp"
#include "ubersim/kernel/plugin_registry.hpp"

namespace {

namespace fs = std::filesystem;
using ubersim::PluginKind;
using ubersim::kernel::ModelError;
using ubersim::kernel::ModelLoader;
using ubersim::kernel::PluginLoadError;
using ubersim::kernel::PluginLookupError;
using ubersim::kernel::PhysicsOverrides;
using ubersim::kernel::PluginSchemaLookup;
using ubersim::kernel::WorldModel;

const fs::path kSource = UBERSIM_SOURCE_DIR;
const fs::path kSchemas = kSource / "schemas";
const fs::path kModels = kSource / "models";

// Accepts every plugin with a schema that allows anything.
const PluginSchemaLookup kAnyPlugin = [](PluginKind, const std::string&) {
  return std::string(R"({"type": "object"})");
};

// An omni drive's own schema, as a plugin would ship it.
const char* const kOmniSchema = R"({
  "$schema": "http://json-schema.org/draft-04/schema#",
  "type": "object",
  "additionalProperties": false,
  "required": ["wheels", "wheel_radius"],
  "properties": {
    "wheels": {"type": "array", "minItems": 3, "items": {
      "type": "object", "additionalProperties": false, "required": ["angle_deg"],
      "properties": {"angle_deg": {"type": "number", "description": "deg"}}}},
    "wheel_radius": {"type": "number", "minimum": 0, "exclusiveMinimum": true, "maximum": 0.1},
    "motor": {"type": "object"}
  }
})";

const PluginSchemaLookup kOmniOnly = [](PluginKind kind, const std::string& id) -> std::string {
  if (kind == PluginKind::kDrive && id == "omni") return kOmniSchema;
  if (kind == PluginKind::kKicker && id == "solenoid") return R"({"type": "object"})";
  if (kind == PluginKind::kTransport && id == "ssl-vision") return "";  // no schema shipped
  throw std::runtime_error("no " + std::string(ubersim::ToString(kind)) + " plugin '" + id +
                           "' in /opt/plugins, /usr/lib/ubersim/plugins");
};

// Field text whose lines are referred to below.
const char* const kField =
    "kind: field\n"                                     // 1
    "name: test-field\n"                                // 2
    "field_length: 9.0\n"                               // 3
    "field_width: 6.0\n"                                // 4
    "boundary_width: 0.3\n"                             // 5
    "center_circle_radius: 0.5\n"                       // 6
    "penalty_area: {depth: 1.0, width: 2.0}\n"          // 7
    "penalty_mark_distance: 6.0\n"                      // 8
    "goal:\n"                                           // 9
    "  width: 1.0\n"                                    // 10
    "  depth: 0.18\n"                                   // 11
    "  height: 0.16\n";                                 // 12

const char* const kRobot =
    "kind: robot\n"                                     // 1
    "name: test-omni\n"                                 // 2
    "body: {mass: 2.3, radius: 0.09, height: 0.146, front_distance: 0.07}\n"  // 3
    "drive:\n"                                          // 4
    "  plugin: omni\n"                                  // 5
    "  wheel_radius: 0.029\n"                           // 6
    "  wheels:\n"                                       // 7
    "    - {angle_deg: 30}\n"                           // 8
    "    - {angle_deg: 150}\n"                          // 9
    "    - {angle_deg: 225}\n"                          // 10
    "    - {angle_deg: 315}\n"                          // 11
    "kicker: {plugin: solenoid, max_flat_speed: 6.5}\n";  // 12

std::string Replace(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  if (at == std::string::npos) throw std::logic_error("test text lacks '" + from + "'");
  return text.replace(at, from.size(), to);
}

class Loader : public ubersim::testing::TempDirTest {
 protected:
  /// The ModelError of `f`, or a marker error when it does not throw.
  template <typename F>
  static ModelError ErrorOf(F&& f) {
    try {
      f();
    } catch (const ModelError& e) {
      return e;
    }
    return ModelError("", 0, 0, "", "(no error)");
  }
  static void Expect(const ModelError& e, const fs::path& file, int line, int column,
                     const std::string& key, const std::string& reason) {
    EXPECT_EQ(e.file(), file.string()) << e.what();
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_EQ(e.column(), column) << e.what();
    EXPECT_EQ(e.key(), key) << e.what();
    EXPECT_EQ(e.reason(), reason) << e.what();
  }
  /// A world naming the shipped field and ball by absolute path, with `extra` appended.
  fs::path WorldWith(const std::string& extra) const {
    return Write("world.yaml", "kind: world\nname: w\nfield: " + (kModels / "fields/div-b.yaml").string() +
                                   "\nball: " + (kModels / "balls/golf.yaml").string() + "\n" + extra);
  }
  ModelLoader loader_{kSchemas, kOmniOnly};
};

// --- the shipped files ------------------------------------------------------------------------

TEST_F(Loader, EveryShippedModelFileValidates) {
  const ModelLoader any(kSchemas, kAnyPlugin);
  int count = 0;
  for (const auto& entry : fs::recursive_directory_iterator(kModels)) {
    if (entry.path().extension() != ".yaml") continue;
    const std::string folder = entry.path().parent_path().filename().string();
    std::string kind;
    ASSERT_NO_THROW(kind = any.Validate(entry.path())) << entry.path();
    EXPECT_EQ(kind + "s", folder) << entry.path();  // fields/ holds kind: field, …
    ++count;
  }
  EXPECT_GE(count, 7);  // 3 fields, 1 ball, 3 worlds
}

TEST_F(Loader, DivBWorldResolvesItsFilesAndFillsEveryModel) {
  const fs::path file = kModels / "worlds/div-b.yaml";
  // The shipped robots' drive blocks are checked by the real plugin's schema elsewhere.
  const auto w = ModelLoader(kSchemas, kAnyPlugin).LoadWorld(file);
  EXPECT_EQ(w.file, file.string());
  EXPECT_EQ(w.name, "div-b");
  ASSERT_TRUE(w.field);
  ASSERT_TRUE(w.ball);
  EXPECT_EQ(w.field->file, (kModels / "fields/div-b.yaml").lexically_normal().string());
  EXPECT_EQ(w.ball->file, (kModels / "balls/golf.yaml").lexically_normal().string());

  const auto& g = w.field->geometry;
  EXPECT_EQ(g.name, "div-b");
  EXPECT_DOUBLE_EQ(g.field_length, 9.0);
  EXPECT_DOUBLE_EQ(g.field_width, 6.0);
  EXPECT_DOUBLE_EQ(g.boundary_width, 0.3);
  EXPECT_DOUBLE_EQ(g.carpet_length, 9.6);
  EXPECT_DOUBLE_EQ(g.carpet_width, 6.6);
  EXPECT_DOUBLE_EQ(g.goal_width, 1.0);
  EXPECT_DOUBLE_EQ(g.goal_depth, 0.18);
  EXPECT_DOUBLE_EQ(g.goal_height, 0.16);
  EXPECT_DOUBLE_EQ(g.penalty_area_depth, 1.0);
  EXPECT_DOUBLE_EQ(g.penalty_area_width, 2.0);
  EXPECT_DOUBLE_EQ(g.center_circle_radius, 0.5);
  EXPECT_DOUBLE_EQ(g.line_thickness, 0.01);
  EXPECT_DOUBLE_EQ(g.goal_center_to_penalty_mark, 6.0);
  EXPECT_EQ(g.lines.size(), 12u);
  EXPECT_EQ(g.arcs.size(), 1u);
  EXPECT_DOUBLE_EQ(w.field->goal_wall_thickness, 0.02);
  EXPECT_DOUBLE_EQ(w.field->wall.height, 0.1);
  EXPECT_DOUBLE_EQ(w.field->wall.thickness, 0.05);
  EXPECT_DOUBLE_EQ(w.field->wall.corner_cut, 0.0);
  EXPECT_EQ(w.field->carpet.name, "carpet");
  EXPECT_EQ(w.field->wall_surface.name, "wall");
  EXPECT_EQ(w.field->goal_surface.name, "goal");

  const auto& b = *w.ball;
  EXPECT_EQ(b.name, "golf");
  EXPECT_DOUBLE_EQ(b.radius, 0.0215);
  EXPECT_DOUBLE_EQ(b.mass, 0.046);
  EXPECT_DOUBLE_EQ(b.inertia_factor, 0.4);
  EXPECT_DOUBLE_EQ(b.linear_damping, 0.0);
  EXPECT_EQ(b.surface.name, "ball");
  EXPECT_DOUBLE_EQ(b.surface.mu, 0.35);
  EXPECT_DOUBLE_EQ(b.surface.bounce, 0.56);
  EXPECT_DOUBLE_EQ(b.surface.rolling_friction, 0.0011);
  EXPECT_DOUBLE_EQ(b.surface.mu2, -1.0);  // SurfaceMaterial default

  EXPECT_EQ(w.ball_start, ubersim::Vec3::Zero());
  ASSERT_EQ(w.robots.size(), 12u);  // 2 × 6
  EXPECT_EQ(w.robots[0].id, (ubersim::RobotId{ubersim::Team::kBlue, 0}));
  EXPECT_EQ(w.robots[6].id, (ubersim::RobotId{ubersim::Team::kYellow, 0}));
  EXPECT_EQ(w.robots[0].model->drive->plugin, "omni");
  // The shipped worlds run the fast profile.
  EXPECT_EQ(w.physics.profile, "fast");
  EXPECT_DOUBLE_EQ(w.physics.step, 0.005);
  EXPECT_EQ(w.physics.solver_iterations, 10);
  EXPECT_EQ(w.physics.IterationsWithoutBall(), 2);
  EXPECT_DOUBLE_EQ(w.physics.erp, 0.2);
  EXPECT_DOUBLE_EQ(w.physics.cfm, 1e-7);
  EXPECT_DOUBLE_EQ(w.physics.gravity.z(), -9.81);
  EXPECT_EQ(w.physics.broadphase, "field");
  EXPECT_EQ(w.physics.max_contacts, 1);
  EXPECT_EQ(w.seed, 1u);
  EXPECT_TRUE(w.plugin_paths.empty());
  // SSL-Vision out, grSim and the simulation protocol in, on their usual ports.
  ASSERT_EQ(w.transports.size(), 4u);
  EXPECT_EQ(w.transports[0].plugin, "ssl_vision");
  EXPECT_EQ(w.transports[0].params.GetInt("port", 0), 10020);
  EXPECT_EQ(w.transports[1].plugin, "grsim");
  EXPECT_EQ(w.transports[1].params.GetInt("port", 0), 20011);
  EXPECT_EQ(w.transports[2].plugin, "ssl_simulation");
  EXPECT_EQ(w.transports[2].params.GetInt("control_port", 0), 10300);
  // Heard and seen wherever the vision goes: loopback and the default route's interface.
  EXPECT_EQ(w.transports[0].params.GetString("interface", ""), "auto");
  EXPECT_EQ(w.transports[1].params.GetString("address", ""), "auto");
  EXPECT_EQ(w.transports[2].params.GetString("address", ""), "auto");
  EXPECT_FALSE(w.local_only);
  EXPECT_EQ(w.transports[3].plugin, "viewer");
  EXPECT_EQ(w.transports[3].params.GetInt("port", 0), 8080);
  EXPECT_EQ(w.perception.preset, "realistic");  // today's league: one camera over Div B, 6 m up
  ASSERT_EQ(w.perception.cameras.size(), 1u);
  EXPECT_EQ(w.perception.cameras[0].position, ubersim::Vec3(0, 0, 6));
  EXPECT_DOUBLE_EQ(w.perception.frame_rate, 75);
  EXPECT_EQ(w.radio.preset, "realistic");

  ASSERT_EQ(w.material_pairs.size(), 9u);
  const auto& bc = w.material_pairs[0];
  EXPECT_EQ(bc.a, "ball");
  EXPECT_EQ(bc.b, "carpet");
  EXPECT_EQ(bc.surface.name, "ball|carpet");
  EXPECT_DOUBLE_EQ(bc.surface.mu, 0.35);
  EXPECT_DOUBLE_EQ(bc.surface.bounce, 0.56);
  EXPECT_DOUBLE_EQ(bc.surface.bounce_velocity, 0.1);
  EXPECT_DOUBLE_EQ(bc.surface.rolling_friction, 0.0011);
  EXPECT_DOUBLE_EQ(bc.surface.soft_erp, -1.0);  // default
  const auto& bg = w.material_pairs[2];
  EXPECT_EQ(bg.surface.name, "ball|goal");
  EXPECT_DOUBLE_EQ(bg.surface.bounce, 0.2);
  const auto& br = w.material_pairs[3];
  EXPECT_EQ(br.surface.name, "ball|robot");
  EXPECT_DOUBLE_EQ(br.surface.mu, 0.18);
}

TEST_F(Loader, DivAHasADeeperMarginBehindTheGoalLines) {
  const auto w = ModelLoader(kSchemas, kAnyPlugin).LoadWorld(kModels / "worlds/div-a.yaml");
  const auto& g = w.field->geometry;
  EXPECT_DOUBLE_EQ(g.field_length, 12.0);
  EXPECT_DOUBLE_EQ(g.field_width, 9.0);
  EXPECT_DOUBLE_EQ(g.boundary_width, 0.3);  // the touch-line margin
  EXPECT_DOUBLE_EQ(g.carpet_length, 13.2);  // 12 + 2 · 0.6
  EXPECT_DOUBLE_EQ(g.carpet_width, 9.6);    // 9 + 2 · 0.3
  EXPECT_DOUBLE_EQ(g.goal_width, 1.8);
  EXPECT_DOUBLE_EQ(g.penalty_area_depth, 1.8);
  EXPECT_DOUBLE_EQ(g.penalty_area_width, 3.6);
  EXPECT_DOUBLE_EQ(g.goal_center_to_penalty_mark, 8.0);
}

TEST_F(Loader, Ssl2003FieldHasAngledCorners) {
  const auto f = loader_.LoadField(kModels / "fields/ssl-2003.yaml");
  EXPECT_DOUBLE_EQ(f->geometry.carpet_length, 2.8);
  EXPECT_DOUBLE_EQ(f->geometry.carpet_width, 2.3);
  EXPECT_DOUBLE_EQ(f->wall.corner_cut, 0.1);
  EXPECT_DOUBLE_EQ(f->geometry.goal_width, 0.5);
}

TEST_F(Loader, Ssl2003WorldHasThePapersVisionSystem) {
  const auto w = ModelLoader(kSchemas, kAnyPlugin).LoadWorld(kModels / "worlds/ssl-2003.yaml");
  EXPECT_EQ(w.perception.preset, "2003");
  EXPECT_DOUBLE_EQ(w.perception.frame_rate, 30);  // the paper: 30 Hz, about 100 ms
  EXPECT_DOUBLE_EQ(w.perception.latency, 0.1);
  ASSERT_EQ(w.perception.cameras.size(), 4u);      // 2 × 2 over the 2.8 × 2.3 m carpet
  EXPECT_DOUBLE_EQ(w.perception.cameras[0].position.x(), -0.7);
  EXPECT_DOUBLE_EQ(w.perception.cameras[0].position.y(), 0.575);
  EXPECT_DOUBLE_EQ(w.perception.cameras[0].position.z(), 4.0);
  EXPECT_EQ(w.radio.preset, "2003");
}

TEST_F(Loader, RobotComponentsCarryTheirOwnParameters) {
  const auto path = Write("robots/r.yaml", kRobot);
  const auto r = loader_.LoadRobot(path);
  EXPECT_EQ(r->name, "test-omni");
  EXPECT_DOUBLE_EQ(r->body.mass, 2.3);
  EXPECT_DOUBLE_EQ(r->body.radius, 0.09);
  EXPECT_DOUBLE_EQ(r->body.height, 0.146);
  EXPECT_DOUBLE_EQ(r->body.front_distance, 0.07);
  EXPECT_DOUBLE_EQ(r->body.ground_clearance, 0.0);
  EXPECT_EQ(r->surface.name, "robot");
  ASSERT_TRUE(r->drive);
  EXPECT_EQ(r->drive->plugin, "omni");
  EXPECT_FALSE(r->drive->params.Has("plugin"));
  EXPECT_DOUBLE_EQ(r->drive->params["wheel_radius"].AsDouble(), 0.029);
  const auto angle = r->drive->params["wheels"].At(3)["angle_deg"];
  EXPECT_DOUBLE_EQ(angle.AsDouble(), 315.0);
  EXPECT_EQ(angle.Path(), "drive.wheels[3].angle_deg");
  EXPECT_EQ(angle.Location(), path.string() + ":11:8");
  EXPECT_FALSE(r->dribbler);
  ASSERT_TRUE(r->kicker);
  EXPECT_EQ(r->kicker->plugin, "solenoid");
  EXPECT_DOUBLE_EQ(r->kicker->params["max_flat_speed"].AsDouble(), 6.5);
}

TEST_F(Loader, ALeaguePresetSetsEveryRealismFieldAndTheWorldsKeysWin) {
  Write("fields/f.yaml", kField);
  const std::string head = "kind: world\nname: w\nfield: ../fields/f.yaml\nball: " + (kModels / "balls/golf.yaml").string() + "\n";
  // RC2021 exactly (reference/ssl-protocols.md §6.1), the held ball with it.
  const auto rc = loader_.LoadWorld(Write("worlds/rc.yaml", head + "realism: RC2021\n"));
  EXPECT_DOUBLE_EQ(rc.perception.ball_position_sigma, 0.0010);
  EXPECT_DOUBLE_EQ(rc.perception.robot_position_sigma, 0.0013);
  EXPECT_DOUBLE_EQ(rc.perception.robot_orientation_sigma, 0.01);
  EXPECT_DOUBLE_EQ(rc.perception.ball_area_sigma, 6.5);
  EXPECT_TRUE(rc.perception.ball_occlusion);
  EXPECT_DOUBLE_EQ(rc.perception.ball_visibility_threshold, 0.4);
  EXPECT_DOUBLE_EQ(rc.perception.camera_overlap, 1.0);
  EXPECT_DOUBLE_EQ(rc.perception.dribbler_false_balls, 0.02);
  EXPECT_DOUBLE_EQ(rc.perception.camera_position_error, 0.0);
  EXPECT_DOUBLE_EQ(rc.perception.ball_drop, 0.05);
  EXPECT_DOUBLE_EQ(rc.perception.robot_drop, 0.0);
  EXPECT_DOUBLE_EQ(rc.perception.latency, 0.035);
  ASSERT_TRUE(rc.perception.processing_time.has_value());
  EXPECT_DOUBLE_EQ(*rc.perception.processing_time, 0.010);
  EXPECT_DOUBLE_EQ(rc.perception.object_offset, 0.0);
  EXPECT_DOUBLE_EQ(rc.radio.loss, 0.03);
  EXPECT_DOUBLE_EQ(rc.radio.response_loss, 0.1);
  EXPECT_DOUBLE_EQ(rc.radio.latency, 0.0);
  EXPECT_TRUE(rc.held_ball);
  // Realistic: the offsets and the command delay; dribbling physical.
  const auto real = loader_.LoadWorld(Write("worlds/real.yaml", head + "realism: Realistic\n"));
  EXPECT_DOUBLE_EQ(real.perception.camera_position_error, 0.1);
  EXPECT_DOUBLE_EQ(real.perception.object_offset, 0.02);
  EXPECT_DOUBLE_EQ(real.perception.robot_drop, 0.02);
  EXPECT_DOUBLE_EQ(real.radio.latency, 0.003);
  EXPECT_FALSE(real.held_ball);
  // The world's own keys over the league's preset, and ÜberSim's own settings.
  const auto mine = loader_.LoadWorld(Write("worlds/mine.yaml", head +
      "realism: RC2021\ndribbling: physical\n"
      "perception: {noise: {ball_position: 0.002, ball_area: 3, growth_per_metre: 0.2}, occlusion: {enabled: false,"
      " visibility_threshold: 0.6}, dribbler_false_balls: 0.5, camera_position_error: 0.05, object_offset: 0.01,"
      " processing_time: 0.004, unsynchronised_cameras: true, capture_jitter: 0.001, exposure: 0.003}\n"
      "radio: {response_loss: 0.2}\n"));
  EXPECT_DOUBLE_EQ(mine.perception.ball_position_sigma, 0.002);
  EXPECT_DOUBLE_EQ(mine.perception.robot_position_sigma, 0.0013);  // the preset's
  EXPECT_DOUBLE_EQ(mine.perception.ball_area_sigma, 3);
  EXPECT_DOUBLE_EQ(mine.perception.noise_growth, 0.2);
  EXPECT_FALSE(mine.perception.ball_occlusion);
  EXPECT_DOUBLE_EQ(mine.perception.ball_visibility_threshold, 0.6);
  EXPECT_DOUBLE_EQ(mine.perception.dribbler_false_balls, 0.5);
  EXPECT_DOUBLE_EQ(mine.perception.camera_position_error, 0.05);
  EXPECT_DOUBLE_EQ(mine.perception.object_offset, 0.01);
  EXPECT_DOUBLE_EQ(*mine.perception.processing_time, 0.004);
  EXPECT_TRUE(mine.perception.unsynchronised_cameras);
  EXPECT_DOUBLE_EQ(mine.perception.capture_jitter, 0.001);
  EXPECT_DOUBLE_EQ(mine.perception.exposure, 0.003);
  EXPECT_DOUBLE_EQ(mine.radio.response_loss, 0.2);
  EXPECT_FALSE(mine.held_ball);
  // A name that is not a league preset is an error at its key.
  try {
    loader_.LoadWorld(Write("worlds/bad.yaml", head + "realism: RC2022\n"));
    FAIL() << "RC2022 accepted";
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("realism"), std::string::npos) << e.what();
  }
}

TEST_F(Loader, WorldRobotsShareTheirModelAndResolveRelativePaths) {
  Write("robots/r.yaml", kRobot);
  const auto world = Write("worlds/w.yaml",
      "kind: world\nname: w\nfield: ../fields/f.yaml\nball: " + (kModels / "balls/golf.yaml").string() +
      "\nball_start: [1.0, -0.5, 0]\n"
      "robots:\n"
      "  - {team: blue, id: 0, model: ../robots/r.yaml, x: -1.0, y: 0.5, yaw: 1.5}\n"
      "  - {team: yellow, id: 0, model: ../robots/r.yaml, x: 1.0, y: 0.0, present: false}\n"
      "seed: 42\nplugin_paths: [../plugins, /abs/plugins]\n"
      "transports:\n  - {plugin: ssl-vision, port: 10006}\n"
      "perception: {preset: realistic, camera_count: 4, latency: 0.02, noise: {ball_position: 0.003}}\n"
      "radio: {preset: '2003', loss: 0.1}\n");
  Write("fields/f.yaml", kField);
  const auto w = loader_.LoadWorld(world);
  EXPECT_EQ(w.field->file, (dir() / "fields/f.yaml").string());
  EXPECT_EQ(w.field->geometry.name, "test-field");
  EXPECT_DOUBLE_EQ(w.field->wall.height, 0.1);  // defaults when the file has no wall block
  EXPECT_DOUBLE_EQ(w.field->geometry.line_thickness, 0.01);
  EXPECT_EQ(w.ball_start, ubersim::Vec3(1.0, -0.5, 0.0));
  ASSERT_EQ(w.robots.size(), 2u);
  EXPECT_EQ(w.robots[0].id.team, ubersim::Team::kBlue);
  EXPECT_EQ(w.robots[1].id.team, ubersim::Team::kYellow);
  EXPECT_DOUBLE_EQ(w.robots[0].x, -1.0);
  EXPECT_DOUBLE_EQ(w.robots[0].y, 0.5);
  EXPECT_DOUBLE_EQ(w.robots[0].yaw, 1.5);
  EXPECT_TRUE(w.robots[0].present);
  EXPECT_FALSE(w.robots[1].present);
  EXPECT_EQ(w.robots[0].model, w.robots[1].model);  // read once
  EXPECT_EQ(w.robots[0].model->file, (dir() / "robots/r.yaml").string());
  EXPECT_EQ(w.seed, 42u);
  ASSERT_EQ(w.plugin_paths.size(), 2u);
  EXPECT_EQ(w.plugin_paths[0], dir() / "plugins");
  EXPECT_EQ(w.plugin_paths[1], fs::path("/abs/plugins"));
  ASSERT_EQ(w.transports.size(), 1u);
  EXPECT_EQ(w.transports[0].plugin, "ssl-vision");
  EXPECT_EQ(w.transports[0].params.GetInt("port", 0), 10006);
  EXPECT_FALSE(w.transports[0].params.Has("plugin"));
  EXPECT_EQ(w.transports[0].params["port"].Path(), "transports[0].port");
  // The preset's defaults, with the keys given on top.
  EXPECT_EQ(w.perception.preset, "realistic");
  EXPECT_DOUBLE_EQ(w.perception.frame_rate, 75.0);
  EXPECT_DOUBLE_EQ(w.perception.latency, 0.02);
  EXPECT_DOUBLE_EQ(w.perception.ball_position_sigma, 0.003);
  EXPECT_DOUBLE_EQ(w.perception.robot_position_sigma, 0.0013);
  ASSERT_EQ(w.perception.cameras.size(), 4u);  // 2 × 2 over the carpet, 6 m up
  const double half_length = 0.5 * w.field->geometry.carpet_length;
  EXPECT_DOUBLE_EQ(w.perception.cameras[0].position.x(), -0.5 * half_length);
  EXPECT_DOUBLE_EQ(w.perception.cameras[0].x_min, -half_length);
  EXPECT_DOUBLE_EQ(w.perception.cameras[3].x_max, half_length);
  EXPECT_DOUBLE_EQ(w.perception.cameras[3].position.z(), 6.0);
  EXPECT_EQ(w.radio.preset, "2003");
  EXPECT_DOUBLE_EQ(w.radio.latency, 0.02);
  EXPECT_DOUBLE_EQ(w.radio.loss, 0.1);
}

TEST_F(Loader, CameraDefinitionsThatCannotWorkAreReportedWhereTheyStand) {
  const auto area = WorldWith("perception:\n  cameras:\n    - {position: [0, 0, 4], area: [1.0, -3, 1.0, 3]}\n");
  Expect(ErrorOf([&] { loader_.LoadWorld(area); }), area, 7, 29, "perception.cameras[0].area",
         "expected [x_min, y_min, x_max, y_max] with x_min < x_max and y_min < y_max");
  const auto twice = WorldWith("perception:\n  cameras:\n    - {id: 3, position: [-2, 0, 4], area: [-4, -3, 0, 3]}\n"
                               "    - {id: 3, position: [2, 0, 4], area: [0, -3, 4, 3]}\n");
  Expect(ErrorOf([&] { loader_.LoadWorld(twice); }), twice, 8, 8, "perception.cameras[1].id",
         "camera id 3 is already used at line 7");
  const auto preset = WorldWith("perception: {preset: perfect}\n");
  Expect(ErrorOf([&] { loader_.LoadWorld(preset); }), preset, 5, 14, "perception.preset",
         "value \"perfect\" is not allowed (allowed: ideal, 2003, realistic)");
}

// --- one test per kind of error, each at its exact place ---------------------------------------

TEST_F(Loader, UnknownKey) {
  const auto path = Write("ball.yaml", "kind: ball\nname: golf\nradius: 0.0215\nmassx: 0.046\n");
  Expect(ErrorOf([&] { loader_.LoadBall(path); }), path, 4, 1, "massx",
         "unknown key 'massx' (allowed: kind, name, radius, mass, inertia_factor, damping, surface); "
         "did you mean 'mass'?");
  // In a nested block.
  const auto field = Write("field.yaml", Replace(kField, "  depth: 0.18\n", "  dept: 0.18\n"));
  Expect(ErrorOf([&] { loader_.LoadField(field); }), field, 11, 3, "goal.dept",
         "unknown key 'dept' (allowed: width, depth, height, wall_thickness); did you mean 'depth'?");
}

TEST_F(Loader, WrongType) {
  const auto path = Write("ball.yaml", "kind: ball\nname: golf\nradius: abc\nmass: 0.046\n");
  Expect(ErrorOf([&] { loader_.LoadBall(path); }), path, 3, 1, "radius",
         "expected a number, got string \"abc\"");
  const auto world = WorldWith("robots:\n  - {team: blue, id: 1.5, model: r.yaml, x: 0, y: 0}\n");
  Expect(ErrorOf([&] { loader_.LoadWorld(world); }), world, 6, 18, "robots[0].id",
         "expected an integer, got number 1.5");
}

TEST_F(Loader, ValueOutOfRange) {
  const auto world = WorldWith("physics:\n  step: 0.5\n");
  Expect(ErrorOf([&] { loader_.LoadWorld(world); }), world, 6, 3, "physics.step",
         "value 0.5 is above the maximum 0.02");
  const auto ball = Write("ball.yaml", "kind: ball\nname: golf\nradius: 0.0215\nmass: -1\n");
  Expect(ErrorOf([&] { loader_.LoadBall(ball); }), ball, 4, 1, "mass", "value -1 must be greater than 0");
  const auto team = WorldWith("robots:\n  - {team: red, id: 1, model: r.yaml, x: 0, y: 0}\n");
  Expect(ErrorOf([&] { loader_.LoadWorld(team); }), team, 6, 6, "robots[0].team",
         "value \"red\" is not allowed (allowed: blue, yellow)");
  const auto id = WorldWith("robots:\n  - {team: blue, id: 16, model: r.yaml, x: 0, y: 0}\n");
  Expect(ErrorOf([&] { loader_.LoadWorld(id); }), id, 6, 18, "robots[0].id",
         "value 16 is above the maximum 15");
}

TEST_F(Loader, IslandsWithoutTheBallMayTakeFewerSolverIterations) {
  const WorldModel plain = loader_.LoadWorld(WorldWith("physics:\n  solver_iterations: 12\n"));
  EXPECT_FALSE(plain.physics.solver_iterations_without_ball);
  EXPECT_EQ(plain.physics.IterationsWithoutBall(), 12);  // absent: as solver_iterations

  const WorldModel fast =
      loader_.LoadWorld(WorldWith("physics:\n  solver_iterations: 10\n  solver_iterations_without_ball: 4\n"));
  EXPECT_EQ(fast.physics.solver_iterations, 10);
  EXPECT_EQ(fast.physics.IterationsWithoutBall(), 4);

  const auto zero = WorldWith("physics:\n  solver_iterations_without_ball: 0\n");
  Expect(ErrorOf([&] { loader_.LoadWorld(zero); }), zero, 6, 3, "physics.solver_iterations_without_ball",
         "value 0 is below the minimum 1");
}

TEST_F(Loader, APhysicsProfileGivesEverySettingAndTheFilesKeysGoOverIt) {
  // No physics block, or one naming no profile: precise, the reference.
  const WorldModel plain = loader_.LoadWorld(WorldWith(""));
  EXPECT_EQ(plain.physics.profile, "precise");
  EXPECT_EQ(plain.physics.step, 0.001);
  EXPECT_EQ(plain.physics.solver_iterations, 20);
  EXPECT_EQ(plain.physics.max_contacts, 4);
  EXPECT_EQ(plain.physics.contact_max_correcting_velocity, 3.0);
  EXPECT_TRUE(plain.physics.world_keys.Keys().empty());

  const WorldModel fast = loader_.LoadWorld(WorldWith("physics:\n  profile: fast\n"));
  EXPECT_EQ(fast.physics.profile, "fast");
  EXPECT_EQ(fast.physics.step, 0.005);
  EXPECT_EQ(fast.physics.solver_iterations, 10);
  EXPECT_EQ(fast.physics.IterationsWithoutBall(), 2);
  EXPECT_EQ(fast.physics.max_contacts, 1);
  EXPECT_EQ(fast.physics.erp, 0.2);

  // A key beside the profile overrides it, and is remembered as the world's own.
  const WorldModel tuned = loader_.LoadWorld(WorldWith("physics:\n  profile: fast\n  solver_iterations: 12\n  erp: 0.4\n"));
  EXPECT_EQ(tuned.physics.step, 0.005);
  EXPECT_EQ(tuned.physics.solver_iterations, 12);
  EXPECT_EQ(tuned.physics.erp, 0.4);
  EXPECT_EQ(tuned.physics.world_keys.Keys(), (std::vector<std::string>{"solver_iterations", "erp"}));

  // Another profile chosen later (--profile) replaces the profile, not the world's own keys.
  WorldModel chosen = tuned;
  PhysicsOverrides flag;
  flag.profile = "precise";
  flag.ApplyTo(chosen.physics);
  EXPECT_EQ(chosen.physics.profile, "precise");
  EXPECT_EQ(chosen.physics.step, 0.001);
  EXPECT_EQ(chosen.physics.solver_iterations, 12);
  EXPECT_EQ(chosen.physics.erp, 0.4);
  EXPECT_FALSE(chosen.physics.solver_iterations_without_ball);
  EXPECT_EQ(DescribePhysics(chosen.physics),
            "profile precise: step 1 ms, 12 solver iterations, 4 contacts per pair; the world sets solver_iterations, erp");
  flag.profile = "quick";
  EXPECT_THROW(flag.ApplyTo(chosen.physics), std::invalid_argument);

  // A name that is no profile is reported where it stands, with the names there are.
  const auto typo = WorldWith("physics:\n  profile: quick\n");
  Expect(ErrorOf([&] { loader_.LoadWorld(typo); }), typo, 6, 3, "physics.profile",
         "value \"quick\" is not allowed (allowed: precise, fast)");
}

TEST(PhysicsProfiles, TheSchemaListsExactlyTheKernelsProfiles) {
  std::ifstream in(kSchemas / "world.schema.json");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::string listed;
  for (const std::string& name : ubersim::kernel::PhysicsProfileNames()) {
    listed += (listed.empty() ? "" : ", ") + ("\"" + name + "\"");
  }
  EXPECT_NE(text.find("\"enum\": [" + listed + "]"), std::string::npos)
      << "world.schema.json's physics.profile enum must list " << listed;
  ubersim::kernel::PhysicsModel p;
  for (const std::string& name : ubersim::kernel::PhysicsProfileNames()) EXPECT_TRUE(PhysicsProfile(name, p)) << name;
  EXPECT_FALSE(PhysicsProfile("quick", p));
}

TEST_F(Loader, MissingRequiredKey) {
  const auto ball = Write("ball.yaml", "# a ball\nkind: ball\nname: golf\nmass: 0.046\n");
  Expect(ErrorOf([&] { loader_.LoadBall(ball); }), ball, 2, 1, "radius", "missing required key 'radius'");
  const auto field = Write("field.yaml", Replace(kField, "  height: 0.16\n", ""));
  Expect(ErrorOf([&] { loader_.LoadField(field); }), field, 9, 1, "goal.height",
         "missing required key 'height'");
  const auto nokind = Write("nokind.yaml", "name: golf\nradius: 0.0215\n");
  Expect(ErrorOf([&] { loader_.Validate(nokind); }), nokind, 1, 1, "kind",
         "missing required key 'kind' (one of: world, field, ball, robot)");
}

TEST_F(Loader, MissingFileDirectly) {
  const auto path = dir() / "no-such-ball.yaml";
  Expect(ErrorOf([&] { loader_.LoadBall(path); }), path, 0, 0, "",
         "cannot open file: No such file or directory");
  Expect(ErrorOf([&] { loader_.Validate(path); }), path, 0, 0, "",
         "cannot open file: No such file or directory");
  Expect(ErrorOf([&] { loader_.LoadWorld(path); }), path, 0, 0, "",
         "cannot open file: No such file or directory");
}

TEST_F(Loader, MissingFileNamedByAWorld) {
  const auto world = Write("w.yaml", "kind: world\nname: w\nfield: fields/none.yaml\nball: b.yaml\n");
  Expect(ErrorOf([&] { loader_.LoadWorld(world); }), world, 3, 1, "field",
         "cannot open field file '" + (dir() / "fields/none.yaml").string() +
             "': No such file or directory");
  Write("fields/none.yaml", kField);
  Expect(ErrorOf([&] { loader_.LoadWorld(world); }), world, 4, 1, "ball",
         "cannot open ball file '" + (dir() / "b.yaml").string() + "': No such file or directory");
  const auto robots = WorldWith("robots:\n  - team: blue\n    id: 3\n    model: ../robots/gone.yaml\n    x: 0\n    y: 0\n");
  Expect(ErrorOf([&] { loader_.LoadWorld(robots); }), robots, 8, 5, "robots[0].model",
         "cannot open robot file '" + (dir().parent_path() / "robots/gone.yaml").string() +
             "': No such file or directory");
}

TEST_F(Loader, FileOfTheWrongKind) {
  const auto world = Write("w.yaml", "kind: world\nname: w\nfield: " + (kModels / "balls/golf.yaml").string() +
                                         "\nball: " + (kModels / "balls/golf.yaml").string() + "\n");
  Expect(ErrorOf([&] { loader_.LoadWorld(world); }), world, 3, 1, "field",
         "'" + (kModels / "balls/golf.yaml").string() + "' is a ball model (kind: ball), expected a field model");
  const auto ball = Write("b.yaml", "kind: ball\nname: x\nradius: 0.02\nmass: 0.04\n");
  Expect(ErrorOf([&] { loader_.LoadField(ball); }), ball, 1, 1, "kind", "expected kind 'field', got 'ball'");
  const auto empty = Write("e.yaml", "# nothing yet\n");
  Expect(ErrorOf([&] { loader_.Validate(empty); }), empty, 1, 1, "",
         "the file is empty (a model file starts with 'kind: world|field|ball|robot')");
  const auto list = Write("l.yaml", "- kind: ball\n");
  Expect(ErrorOf([&] { loader_.Validate(list); }), list, 1, 1, "",
         "expected a mapping of keys at the top level (a model file starts with "
         "'kind: world|field|ball|robot'), got an array");
  const auto odd = Write("o.yaml", "kind: referee\n");
  Expect(ErrorOf([&] { loader_.Validate(odd); }), odd, 1, 1, "kind",
         "unknown kind 'referee' (allowed: world, field, ball, robot)");
}

TEST_F(Loader, TextInMemoryIsCheckedAsTheFileItNames) {
  // Nothing is written: the name only places the text, for messages and relative paths.
  const auto name = dir() / "worlds" / "typed-in.yaml";
  EXPECT_EQ(loader_.ValidateText(kField, name), "field");
  Expect(ErrorOf([&] { loader_.ValidateText("kind: ball\nname: golf\nradius: 0.0215\nmass: -1\n", name); }), name,
         4, 1, "mass", "value -1 must be greater than 0");
  Expect(ErrorOf([&] { loader_.ValidateText("kind: ball\nname: x\nradius: 0.02\n  mass: 1\n", name); }), name, 4,
         7, "", "YAML syntax error: illegal map value");
  // A world's relative paths resolve against the named file's folder.
  Write("fields/f.yaml", kField);
  const std::string world = "kind: world\nname: w\nfield: ../fields/f.yaml\nball: ../balls/none.yaml\n";
  Expect(ErrorOf([&] { loader_.ValidateText(world, name); }), name, 4, 1, "ball",
         "cannot open ball file '" + (dir() / "balls/none.yaml").string() + "': No such file or directory");
  Write("balls/none.yaml", "kind: ball\nname: x\nradius: 0.02\nmass: 0.04\n");
  EXPECT_EQ(loader_.ValidateText(world, name), "world");
}

TEST_F(Loader, YamlSyntaxError) {
  const auto path = Write("ball.yaml", "kind: ball\nname: golf\nradius: 0.0215\n  mass: 0.046\n");
  Expect(ErrorOf([&] { loader_.LoadBall(path); }), path, 4, 7, "", "YAML syntax error: illegal map value");
  // In a file named by a world: reported in that file.
  const auto world = Write("w.yaml", "kind: world\nname: w\nfield: " + (kModels / "fields/div-b.yaml").string() +
                                         "\nball: ball.yaml\n");
  Expect(ErrorOf([&] { loader_.LoadWorld(world); }), path, 4, 7, "", "YAML syntax error: illegal map value");
}

TEST_F(Loader, UnknownPlugin) {
  const auto path = Write("r.yaml", Replace(kRobot, "  plugin: omni\n", "  plugin: warp\n"));
  Expect(ErrorOf([&] { loader_.LoadRobot(path); }), path, 5, 3, "drive.plugin",
         "unknown plugin 'warp': no drive plugin 'warp' in /opt/plugins, /usr/lib/ubersim/plugins");
  const auto world = WorldWith("transports:\n  - {plugin: carrier-pigeon}\n");
  Expect(ErrorOf([&] { loader_.LoadWorld(world); }), world, 6, 6, "transports[0].plugin",
         "unknown plugin 'carrier-pigeon': no transport plugin 'carrier-pigeon' in /opt/plugins, "
         "/usr/lib/ubersim/plugins");
  const auto dribbler = Write("d.yaml", std::string(kRobot) + "dribbler: {plugin: omni}\n");
  Expect(ErrorOf([&] { loader_.LoadRobot(dribbler); }), dribbler, 13, 12, "dribbler.plugin",
         "unknown plugin 'omni': no dribbler plugin 'omni' in /opt/plugins, /usr/lib/ubersim/plugins");
}

// `ubersim validate` and `ubersim run` agree on a robot file: its URDF is read when the robot
// file is loaded, not only when a robot is built from it.
TEST_F(Loader, ARobotsUrdfIsReadWhenTheRobotFileIsLoaded) {
  const std::string inertial =
      "<inertial><mass value=\"2.3\"/><inertia ixx=\"0.01\" ixy=\"0\" ixz=\"0\" iyy=\"0.01\" iyz=\"0\" izz=\"0.01\"/></inertial>";
  const auto robot = Write("r.yaml", Replace(kRobot, "name: test-omni\n", "name: test-omni\nurdf: r.urdf\n"));

  // A link without a mass: the URDF's own error, at its line.
  Write("r.urdf", "<robot name=\"r\">\n  <link name=\"base_link\"/>\n</robot>\n");
  const ModelError no_mass = ErrorOf([&] { loader_.LoadRobot(robot); });
  EXPECT_EQ(no_mass.file(), (dir() / "r.urdf").string()) << no_mass.what();
  EXPECT_EQ(no_mass.line(), 2) << no_mass.what();
  EXPECT_NE(no_mass.reason().find("positive mass"), std::string::npos) << no_mass.what();

  // A root link heavier than body.mass: reported at body.mass in the robot file.
  Write("r.urdf", "<robot name=\"r\">\n  <link name=\"base_link\">" + Replace(inertial, "2.3", "3.1") +
                      "</link>\n</robot>\n");
  const ModelError mass = ErrorOf([&] { loader_.LoadRobot(robot); });
  EXPECT_EQ(mass.file(), robot.string()) << mass.what();
  EXPECT_EQ(mass.line(), 4) << mass.what();
  EXPECT_EQ(mass.key(), "body.mass") << mass.what();
  EXPECT_NE(mass.reason().find("root link 'base_link' mass 3.1 kg"), std::string::npos) << mass.what();

  // A good one loads.
  Write("r.urdf", "<robot name=\"r\">\n  <link name=\"base_link\">" + inertial + "</link>\n</robot>\n");
  EXPECT_EQ(loader_.LoadRobot(robot)->urdf_file, (dir() / "r.urdf").lexically_normal().string());
}

// A plugin found and refused is not "unknown": the loader says it is refused and why, located at
// the plugin key, as a PluginLookupError (the CLI's plugin error, exit 4).
TEST_F(Loader, ARefusedPluginIsCalledRefusedNotUnknown) {
  const ModelLoader refusing(kSchemas, [](PluginKind, const std::string&) -> std::string {
    throw PluginLoadError("plugin 'omni' (drive)", "refused: /opt/plugins/libubersim_omni.so: built for plugin ABI 6");
  });
  const auto path = Write("r.yaml", kRobot);
  try {
    refusing.LoadRobot(path);
    ADD_FAILURE() << "loaded";
  } catch (const PluginLookupError& e) {
    Expect(e, path, 5, 3, "drive.plugin",
           "plugin 'omni' is refused: refused: /opt/plugins/libubersim_omni.so: built for plugin ABI 6");
  }
  // Not found stays "unknown plugin", and is a PluginLookupError too.
  const auto unknown = Write("u.yaml", Replace(kRobot, "  plugin: omni\n", "  plugin: warp\n"));
  EXPECT_THROW(loader_.LoadRobot(unknown), PluginLookupError);
}

TEST_F(Loader, PluginThatFailsToLoad) {
  const ModelLoader broken(kSchemas, [](PluginKind, const std::string&) -> std::string {
    throw std::runtime_error(
        "/opt/plugins/libubersim_drive_omni.so: cannot load: /opt/plugins/libubersim_drive_omni.so: "
        "undefined symbol: _ZN7ubersim2v14Body4WakeEv");
  });
  const auto path = Write("r.yaml", kRobot);
  Expect(ErrorOf([&] { broken.LoadRobot(path); }), path, 5, 3, "drive.plugin",
         "unknown plugin 'omni': /opt/plugins/libubersim_drive_omni.so: cannot load: "
         "/opt/plugins/libubersim_drive_omni.so: undefined symbol: _ZN7ubersim2v14Body4WakeEv");
}

TEST_F(Loader, PluginParametersFailThePluginsSchema) {
  const auto typo = Write("a.yaml", Replace(kRobot, "  wheel_radius: 0.029\n", "  wheel_radiu: 0.029\n"));
  Expect(ErrorOf([&] { loader_.LoadRobot(typo); }), typo, 6, 3, "drive.wheel_radiu",
         "unknown key 'wheel_radiu' (allowed: wheels, wheel_radius, motor); did you mean 'wheel_radius'?");
  const auto type = Write("b.yaml", Replace(kRobot, "{angle_deg: 225}", "{angle_deg: south}"));
  Expect(ErrorOf([&] { loader_.LoadRobot(type); }), type, 10, 8, "drive.wheels[2].angle_deg",
         "expected a number, got string \"south\"");
  const auto range = Write("c.yaml", Replace(kRobot, "  wheel_radius: 0.029\n", "  wheel_radius: 0.29\n"));
  Expect(ErrorOf([&] { loader_.LoadRobot(range); }), range, 6, 3, "drive.wheel_radius",
         "value 0.29 is above the maximum 0.1");
  const auto missing = Write("d.yaml", Replace(kRobot, "  wheel_radius: 0.029\n", ""));
  Expect(ErrorOf([&] { loader_.LoadRobot(missing); }), missing, 4, 1, "drive.wheel_radius",
         "missing required key 'wheel_radius'");
  // Without a lookup the plugin blocks are not checked.
  const ModelLoader unchecked(kSchemas, nullptr);
  EXPECT_NO_THROW(unchecked.LoadRobot(typo));
}

TEST_F(Loader, APluginSchemaThatRequiresThePluginKeyIsCalledOut) {
  // `plugin:` is taken out before the plugin's schema sees the block: "missing 'plugin'" would
  // send the team to its model file, where the key is.
  const PluginSchemaLookup wants_plugin = [](PluginKind, const std::string&) {
    return std::string(R"({"type": "object", "required": ["plugin"]})");
  };
  const ModelLoader loader(kSchemas, wants_plugin);
  const auto robot = Write("r.yaml", kRobot);
  Expect(ErrorOf([&] { loader.LoadRobot(robot); }), robot, 5, 3, "drive.plugin",
         "the schema of drive plugin 'omni' requires a 'plugin' key, but `plugin:` names the plugin and is "
         "taken out of the block before its schema sees it: remove \"plugin\" from the schema's \"required\" "
         "(docs/plugins.md, Parameters)");
}

TEST_F(Loader, SizesThatDoNotFitTogether) {
  const auto narrow = Write("f.yaml", Replace(kField, "field_width: 6.0\n", "field_width: 0.9\n"));
  Expect(ErrorOf([&] { loader_.LoadField(narrow); }), narrow, 10, 3, "goal.width",
         "the goal (1 m) must be narrower than the field (0.9 m)");
  const auto deep = Write("g.yaml", Replace(kField, "{depth: 1.0,", "{depth: 5.0,"));
  Expect(ErrorOf([&] { loader_.LoadField(deep); }), deep, 7, 16, "penalty_area.depth",
         "the defense area depth (5 m) must be less than half the field length (4.5 m)");
  const auto front = Write("r.yaml", Replace(kRobot, "front_distance: 0.07", "front_distance: 0.1"));
  Expect(ErrorOf([&] { loader_.LoadRobot(front); }), front, 3, 48, "body.front_distance",
         "the flat front (0.1 m from the centre) lies outside the radius (0.09 m)");
}

TEST_F(Loader, DuplicateRobotPlacement) {
  Write("r.yaml", kRobot);
  const auto world = WorldWith(
      "robots:\n"
      "  - {team: blue, id: 2, model: r.yaml, x: 0, y: 0}\n"
      "  - {team: blue, id: 2, model: r.yaml, x: 1, y: 0}\n");
  Expect(ErrorOf([&] { loader_.LoadWorld(world); }), world, 7, 18, "robots[1].id",
         "robot blue 2 is already placed at line 6");
  const auto outside = WorldWith("robots:\n  - {team: blue, id: 2, model: r.yaml, x: 5.0, y: 0}\n");
  Expect(ErrorOf([&] { loader_.LoadWorld(outside); }), outside, 6, 40, "robots[0].x",
         "x 5 m lies outside the walls (|x| ≤ 4.8 m)");
}

TEST(SchemaDir, EnvironmentOverridesAndTheSourceTreeIsTheFallback) {
  ::setenv("UBERSIM_SCHEMA_DIR", "/somewhere/schemas", 1);
  EXPECT_EQ(ModelLoader::DefaultSchemaDir(), fs::path("/somewhere/schemas"));
  ::unsetenv("UBERSIM_SCHEMA_DIR");
  const fs::path found = ModelLoader::DefaultSchemaDir();
  EXPECT_TRUE(fs::exists(found / "world.schema.json")) << found;
  EXPECT_TRUE(fs::exists(found / "robot.schema.json")) << found;
}

TEST(SchemaDir, MissingSchemaFileIsReported) {
  const ModelLoader loader("/no/such/dir", nullptr);
  try {
    loader.LoadBall(kModels / "balls/golf.yaml");
    FAIL() << "no error";
  } catch (const ModelError& e) {
    EXPECT_EQ(e.file(), "/no/such/dir/ball.schema.json");
    EXPECT_EQ(e.line(), 0);
  }
}

}  // namespace
