// SPDX-License-Identifier: Apache-2.0
// Models and their loader: the typed, validated contents of the model files (world, field, ball,
// robot; models/*/*.yaml), the loader that reads and checks them, and ModelError, which says
// where a file is wrong (file, line, column, key path) and why. Also the vision and radio models
// a world file describes, with their presets. SI units throughout.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "ubersim/component.hpp"
#include "ubersim/events.hpp"
#include "ubersim/math.hpp"
#include "ubersim/params.hpp"
#include "ubersim/plugin_kind.hpp"
#include "ubersim/scene.hpp"
#include "ubersim/world_state.hpp"

namespace ubersim::kernel {

/// An error in a model file, saying where (file, line, column, key path) and why.
class ModelError : public std::runtime_error {
 public:
  /// line/column are 1-based; 0 when unknown (e.g. a missing file). key is the dotted path
  /// ("drive.wheels[2].angle_deg"), empty for the whole file.
  ModelError(std::string file, int line, int column, std::string key, std::string reason);

  const std::string& file() const { return file_; }      ///< model file path
  int line() const { return line_; }                     ///< 1-based line, 0 unknown
  int column() const { return column_; }                 ///< 1-based column, 0 unknown
  const std::string& key() const { return key_; }        ///< key path
  const std::string& reason() const { return reason_; }  ///< what is wrong

 private:
  std::string file_;
  int line_;
  int column_;
  std::string key_;
  std::string reason_;
};

/// A model file names a plugin that cannot be used: not found in the search path, or found and
/// refused (the reason says which, and why). Located at the `plugin:` key like any ModelError;
/// the CLI exits 4 for it, as for any plugin error.
class PluginLookupError : public ModelError {
 public:
  using ModelError::ModelError;
};

/// One overhead camera: where it hangs and the part of the carpet it is responsible for.
struct CameraModel {
  int id = 0;                        ///< camera_id in the packets
  Vec3 position = Vec3(0, 0, 6);     ///< field frame, m
  double x_min = 0, y_min = 0;       ///< its part of the carpet (before overlap), m
  double x_max = 0, y_max = 0;       ///< m
};

/// The vision system a world simulates (the world file's `perception:` block, presets resolved).
struct PerceptionModel {
  std::string preset = "ideal";          ///< ideal, 2003 or realistic: the defaults it started from
  double frame_rate = 60.0;              ///< frames per second per camera, Hz
  double latency = 0.0;                  ///< capture to send (t_sent - t_capture), s
  double ball_position_sigma = 0.0;      ///< Gaussian noise on the ball's x and y, m
  double robot_position_sigma = 0.0;     ///< on robots' x and y, m
  double robot_orientation_sigma = 0.0;  ///< on robots' heading, rad
  double ball_drop = 0.0;                ///< probability a camera frame misses the ball
  double robot_drop = 0.0;               ///< probability a camera frame misses a robot
  double camera_overlap = 0.3;           ///< each camera sees this far past its part, m
  std::vector<CameraModel> cameras;      ///< at least one
  // The league's realism (reference/ssl-protocols.md §6.1, RealismConfigErForce):
  bool ball_occlusion = false;             ///< robots between the ball and a camera hide (part of) it
  double ball_visibility_threshold = 0.4;  ///< with occlusion: below this visible fraction, no ball (0: always)
  double ball_area_sigma = 0.0;            ///< σ on the ball blob's area, pixels
  double dribbler_false_balls = 0.0;       ///< false ball detections at a dribbler corner, 1/s per robot
  double camera_position_error = 0.0;      ///< m, added to the reported camera positions only
  double object_offset = 0.0;              ///< m, reported positions shifted away from the centre towards the camera
  /// t_sent − t_capture as the frames report it, s; unset: the latency (the capture time is true).
  std::optional<double> processing_time;
  // Beyond the league's presets (docs/interfaces.md, reference/physics.md §4):
  bool unsynchronised_cameras = false;     ///< each camera its own frame phase, as on a real field
  double capture_jitter = 0.0;             ///< σ of each capture's time about its schedule, s
  double noise_growth = 0.0;               ///< noise σ grows by this fraction per metre from the camera's nadir, 1/m
  double exposure = 0.0;                   ///< s: a moving ball's blob smears along its motion over it
};

/// The radio between the teams' software and the robots (the `radio:` block, presets resolved).
struct RadioModel {
  std::string preset = "ideal";  ///< ideal, 2003 or realistic
  double latency = 0.0;          ///< from arrival to taking effect, s
  double loss = 0.0;             ///< probability a command is lost
  double response_loss = 0.0;    ///< probability a robot's feedback to its team is lost
};

/// Defaults of a preset ("ideal", "2003", "realistic"); false for an unknown name.
bool PerceptionPreset(const std::string& name, PerceptionModel& model);
/// Defaults of a radio preset; false for an unknown name.
bool RadioPreset(const std::string& name, RadioModel& model);
/// The league's realism presets as the ER-Force simulator names them (None, Friendly, RC2021,
/// Realistic; any case), every field of RealismConfigErForce exactly, put over `vision`, `radio`
/// and `held_ball` (simulate_dribbling false). Frame rate and cameras stay; what only ÜberSim
/// models (unsynchronised cameras, capture jitter, noise growth, exposure) is switched off, so
/// the vision is ER-Force's exactly. False for an unknown name.
bool LeagueRealismPreset(const std::string& name, PerceptionModel& vision, RadioModel& radio, bool& held_ball);
/// The league's preset names, for messages: "None, Friendly, RC2021, Realistic".
const char* LeagueRealismPresetNames();

/// `count` cameras over a carpet of length × width (m): a grid, two rows once there are four or
/// more, each camera above the centre of its cell at `height`.
std::vector<CameraModel> CameraGrid(int count, double length, double width, double height);
/// The cameras `now` laid out anew over another field's carpet: as many (at least one), as high.
std::vector<CameraModel> CamerasOver(const std::vector<CameraModel>& now, const FieldGeometry& field);


/// Surface pair entry of a world's material table: the surface used when `a` touches `b`.
struct MaterialPair {
  std::string a;             ///< material name
  std::string b;             ///< material name
  SurfaceMaterial surface;   ///< contact parameters for the pair (its name is "a|b")
};

/// The perimeter wall.
struct WallModel {
  double height = 0.1;       ///< m
  double thickness = 0.05;   ///< m
  double corner_cut = 0.0;   ///< length of the short angled wall across each corner (2003 field), m; 0: square corners
};

/// A field model file (kind: field).
struct FieldModel {
  std::string file;                 ///< where it was read
  FieldGeometry geometry;           ///< sizes and markings (lines and arcs filled in by the loader)
  double goal_wall_thickness = 0.02;  ///< m
  WallModel wall;                   ///< perimeter wall
  SurfaceMaterial carpet;           ///< name "carpet" unless the file says otherwise
  SurfaceMaterial wall_surface;     ///< name "wall"
  SurfaceMaterial goal_surface;     ///< name "goal" (inner faces are foam in the rules)
};

/// A ball model file (kind: ball).
struct BallModel {
  std::string file;           ///< where it was read
  std::string name;           ///< e.g. "golf"
  double radius = 0.0215;     ///< m
  double mass = 0.046;        ///< kg
  double inertia_factor = 0.4;  ///< I = factor · m · r² (0.4 solid sphere, 0.667 thin shell)
  double linear_damping = 0.0;  ///< ODE body linear damping per step (0 = none)
  double angular_damping = 0.0; ///< ODE body angular damping per step (0 = none)
  SurfaceMaterial surface;    ///< name "ball" unless the file says otherwise
};

/// A plugin reference in a model file: which plugin and its own validated parameter block.
struct ComponentModel {
  std::string plugin;    ///< plugin id, e.g. "omni"
  ParamView params;      ///< the block (everything under the component key except `plugin`)
};

/// A robot model file (kind: robot).
struct RobotModel {
  std::string file;                        ///< where it was read
  std::string name;                        ///< e.g. "example-omni-2026"
  RobotBodyInfo body;                      ///< chassis dimensions and mass
  SurfaceMaterial surface;                 ///< chassis surface (name "robot" unless given)
  /// URDF file (absolute) whose links, inertias, joints and collision meshes build the robot's
  /// bodies instead of the `body:` cylinder; empty when the body is given inline.
  std::string urdf_file;
  std::optional<ComponentModel> drive;     ///< the drive
  std::optional<ComponentModel> dribbler;  ///< optional dribbler
  std::optional<ComponentModel> kicker;    ///< optional kicker
  /// QuickStep iterations at least for the islands this robot is in (0: the world's count); a
  /// drive that needs more than the fast profile's 2 for islands without the ball asks here.
  int min_solver_iterations = 0;
  /// The robot file's `dribbling:` (true held, false physical); none: the world's.
  std::optional<bool> held_ball;
  ParamView source;                        ///< the file's tree as read (robot specs edit a copy)
};

/// What a RobotSpec makes of a robot model (ModelLoader::ApplySpec).
struct SpecOutcome {
  std::shared_ptr<const RobotModel> model;  ///< the model with the spec over it; null when a value was refused
  std::vector<std::string> errors;          ///< one per refused value: "mass -1 kg: …"
  std::vector<std::string> unmapped;        ///< the spec's fields the model has no place for
};

/// One robot placed in a world.
struct RobotPlacement {
  RobotId id;                               ///< team and id
  std::shared_ptr<const RobotModel> model;  ///< its model
  double x = 0, y = 0, yaw = 0;             ///< start pose on the field, m and rad
  bool present = true;                      ///< on the field at start
};

struct PhysicsModel;

/// Physics keys set one by one over a profile: a world file's `physics:` block, or the command
/// line's --profile, --physics-step, … (bench, batch, soak, run, validate-physics).
struct PhysicsOverrides {
  /// Another profile than the world's; the world file's own keys still apply over it.
  std::optional<std::string> profile;
  std::optional<double> step;                         ///< fixed physics step, s
  std::optional<int> solver_iterations;               ///< QuickStep iterations
  std::optional<int> solver_iterations_without_ball;  ///< QuickStep iterations of islands without a ball
  std::optional<double> erp;                          ///< global ERP
  std::optional<double> cfm;                          ///< global CFM, m/N
  std::optional<Vec3> gravity;                        ///< m/s²
  std::optional<std::string> broadphase;              ///< "field", "sap", "scene_graph" or "hash"
  std::optional<int> max_contacts;                    ///< contacts per geometry pair
  std::optional<double> contact_surface_layer;        ///< m
  std::optional<double> contact_max_correcting_velocity;  ///< m/s
  std::optional<bool> speculative_robot_contacts;         ///< robots meet at their surface
  std::optional<double> robot_contact_erp;                ///< ERP of robot–robot contacts
  /// True when any is set.
  bool Any() const { return profile || !Keys().empty(); }
  /// The keys set (not the profile), named as in world files, in the schema's order.
  std::vector<std::string> Keys() const;
  /// Sets those given in `physics`; a profile first replaces every setting with the profile's and
  /// then puts the world's own keys (`physics.world_keys`) back over it. Throws
  /// std::invalid_argument for a profile that does not exist.
  void ApplyTo(PhysicsModel& physics) const;
};

/// Physics settings of a world: a named profile, and the keys its file set over it.
struct PhysicsModel {
  std::string profile = "precise";  ///< the profile in force (PhysicsProfileNames)
  PhysicsOverrides world_keys;      ///< the keys the world file set over the profile
  double step = 0.001;             ///< fixed physics step, s
  int solver_iterations = 20;      ///< QuickStep iterations (every island; the ball's islands)
  /// QuickStep iterations for islands no ball belongs to; unset: solver_iterations
  std::optional<int> solver_iterations_without_ball;
  /// Iterations for islands no ball belongs to.
  int IterationsWithoutBall() const { return solver_iterations_without_ball.value_or(solver_iterations); }
  double erp = 0.2;                ///< global ERP
  double cfm = 1e-7;               ///< global CFM
  Vec3 gravity = Vec3(0, 0, -9.81);  ///< m/s²
  std::string broadphase = "field";  ///< "field" (measured fastest), "sap", "scene_graph" or "hash"
  int max_contacts = 4;            ///< contacts per geometry pair
  double contact_surface_layer = 0.0005;  ///< m
  /// m/s: penetrations are undone at most this fast (the robots' top speed; faster threw a robot
  /// teleported onto another over the walls)
  double contact_max_correcting_velocity = 3.0;
  /// Robots about to meet get their contacts a step early, closing only their gap in the step
  /// (CollisionManager::SetSweptRobotStep): a 6 m/s crash closes 30 mm in a 5 ms step
  bool speculative_robot_contacts = false;
  /// ERP of the contacts between two robots' shells; unset: `erp`. ERP is a share of the depth
  /// removed per step: at 5 ms, 0.2 makes a contact five times softer than at 1 ms
  std::optional<double> robot_contact_erp;
};

/// The physics profiles' names: "precise" (1 ms steps, the reference) and "fast" (5 ms steps).
const std::vector<std::string>& PhysicsProfileNames();
/// Sets every setting of `physics` to the named profile's (and `profile` to its name, world_keys
/// cleared); false, changing nothing, for a name that is not a profile.
bool PhysicsProfile(const std::string& name, PhysicsModel& physics);
/// "profile fast: step 5 ms, 10 solver iterations (2 without the ball), 1 contact per pair", and
/// the keys the world set over it.
std::string DescribePhysics(const PhysicsModel& physics);

/// A transport instance of a world.
struct TransportModel {
  std::string plugin;   ///< plugin id
  ParamView params;     ///< its parameter block
};

/// A world file (kind: world).
struct WorldModel {
  std::string file;                          ///< where it was read
  std::string name;                          ///< world name
  std::shared_ptr<const FieldModel> field;   ///< the field
  std::shared_ptr<const BallModel> ball;     ///< the ball
  Vec3 ball_start = Vec3::Zero();            ///< ball start position (z: 0 means resting on the carpet)
  std::vector<RobotPlacement> robots;        ///< every robot
  PhysicsModel physics;                      ///< physics settings
  std::uint64_t seed = 1;                    ///< seed of every random process in the world
  std::vector<std::filesystem::path> plugin_paths;  ///< extra plugin folders, resolved against the file
  std::vector<TransportModel> transports;    ///< transports to start
  std::vector<MaterialPair> material_pairs;  ///< contact table
  PerceptionModel perception;                ///< cameras, frame rate, latency, noise, drop-outs
  RadioModel radio;                          ///< command latency and loss
  /// What a plugin fault does: "stop" (the default: the world stops after the step, state
  /// saved) or "disable" (the plugin is switched off and the world carries on); fault.hpp.
  std::string on_plugin_fault = "stop";
  /// Other fields the world may be switched to while it runs (`fields:`; a client's geometry of
  /// that size, `ubersim run --field`), besides `field`.
  std::vector<std::shared_ptr<const FieldModel>> other_fields;
  /// The robot model of each team's robots that come on while the world runs (`teams:`; else
  /// the model of the team's first robot, else of the other team's): [blue, yellow], may be null.
  std::array<std::shared_ptr<const RobotModel>, 2> team_models;
  /// Every transport on loopback only (`local_only: true`, `ubersim run --local-only`).
  bool local_only = false;
  /// Dribblers hold the ball by a constraint once they touch it, as ER-Force's "perfect
  /// dribbling" (`dribbling: held`; the league's RC2021 preset); false: by contact friction.
  bool held_ball = false;
  /// The world file's `match:` block (referee, tracker, match length; docs/match.md), checked
  /// against the schema and read by the apps that run a match; empty when absent.
  ParamView match;
};

/// Gives the JSON Schema of a plugin's parameter block, or throws saying why the plugin is
/// unavailable: a PluginLoadError (plugin_registry.hpp) whose not_found() is false means it was
/// found and refused; any other exception, that it is unknown (not found, the paths searched).
using PluginSchemaLookup =
    std::function<std::string(PluginKind kind, const std::string& plugin_id)>;

/// Loads and validates model files. Every failure is a ModelError naming file:line:column and key.
class ModelLoader {
 public:
  /// schema_dir holds <kind>.schema.json (world, field, ball, robot); plugin_schema may be empty,
  /// then plugin parameter blocks are not checked.
  ModelLoader(std::filesystem::path schema_dir, PluginSchemaLookup plugin_schema);

  /// Reads a world file and everything it names (field, ball, robots), resolving relative paths
  /// against the file that names them.
  WorldModel LoadWorld(const std::filesystem::path& file) const;
  /// Reads a field file.
  std::shared_ptr<const FieldModel> LoadField(const std::filesystem::path& file) const;
  /// Reads a ball file.
  std::shared_ptr<const BallModel> LoadBall(const std::filesystem::path& file) const;
  /// Reads a robot file (checking its plugins' parameter blocks).
  std::shared_ptr<const RobotModel> LoadRobot(const std::filesystem::path& file) const;
  /// `base` with `spec` over it, checked as a model file is: each value alone (one error per
  /// refused value), then all together. Body values go to the body block; the others to the
  /// plugin parameters whose schema names the field (`"robot_spec": "max_speed"`); a field
  /// with no such place is listed in `unmapped`. The model keeps base's file; its name says it
  /// carries robot specs.
  SpecOutcome ApplySpec(const RobotModel& base, const RobotSpec& spec) const;
  /// Reads any model file by its `kind:` and validates it fully (for `ubersim validate`);
  /// returns the kind.
  std::string Validate(const std::filesystem::path& file) const;
  /// As Validate, for model text already in memory: `file` names it in errors, and relative
  /// paths in it resolve against the folder of `file` (which need not exist as a file).
  std::string ValidateText(const std::string& text, const std::filesystem::path& file) const;

  /// The installed or source-tree schemas/ folder, found relative to the running executable.
  static std::filesystem::path DefaultSchemaDir();

 private:
  struct Impl;
  std::shared_ptr<const Impl> impl_;
};

/// Parses a YAML file into a located tree; throws ModelError (missing file, syntax error).
std::shared_ptr<const detail::ParamNode> ParseYamlFile(const std::filesystem::path& file);
/// Parses YAML text (file names the source in errors).
std::shared_ptr<const detail::ParamNode> ParseYamlText(const std::string& text, const std::string& file);

/// Validates `value` against draft-04 JSON Schema text; throws ModelError at the offending value,
/// naming its key path. `schema_label` names the schema in the message.
void ValidateAgainstSchema(const ParamView& value, const std::string& schema_json,
                           const std::string& schema_label);
/// `value` with every key its draft-04 JSON Schema gives a `default` and the value leaves out
/// filled in, in objects that are there (nested objects and array items too): what the loader
/// hands a plugin, so that the schema's defaults are the ones in force. Filled values carry the
/// location of the object they were put in. Throws ModelError when the schema is not valid JSON.
ParamView WithSchemaDefaults(const ParamView& value, const std::string& schema_json,
                             const std::string& schema_label);

/// Fills geometry.lines and geometry.arcs from the sizes, as SSL-Vision names them
/// ("TopTouchLine", "LeftGoalLine", "CenterCircle", …).
void BuildFieldMarkings(FieldGeometry& geometry);

}  // namespace ubersim::kernel
