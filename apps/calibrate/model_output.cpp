// SPDX-License-Identifier: Apache-2.0
#include "model_output.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

namespace ubersim::calibrate {
namespace fs = std::filesystem;
namespace {

// Four significant digits, as text: more than any fit here resolves, and yaml-cpp would turn a
// double into all seventeen.
std::string Round4(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

// A length to the millimetre, as text.
std::string Millimetres(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f", std::abs(v) < 5e-4 ? 0.0 : v);
  std::string s = buf;
  while (s.size() > 1 && s.back() == '0') s.pop_back();
  if (s.back() == '.') s.pop_back();
  return s;
}

YAML::Node Load(const fs::path& file) {
  try {
    return YAML::LoadFile(file.string());
  } catch (const YAML::Exception& e) {
    throw std::runtime_error("cannot read " + file.string() + ": " + e.what());
  }
}

void Write(const fs::path& file, const std::string& header, const YAML::Node& node) {
  YAML::Emitter out;
  out.SetDoublePrecision(6);
  out << node;
  std::ofstream f(file);
  f << header << out.c_str() << "\n";
  if (!f) throw std::runtime_error("cannot write " + file.string());
}

// A path a base file names (relative to its own folder) as the output folder should name it.
std::string Rebased(const std::string& path, const fs::path& base_dir, const fs::path& out_dir) {
  fs::path p(path);
  if (p.is_relative()) p = base_dir / p;
  p = p.lexically_normal();
  std::error_code ec;
  const fs::path rel = fs::relative(p, out_dir, ec);
  return ec || rel.empty() ? p.string() : rel.string();
}

std::string Comment(const std::string& text) {
  std::string out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out += line.empty() ? "#\n" : "# " + line + "\n";
  return out;
}

// Sets `key` to the estimate when there is one inside the model's range [low, high] (the
// schemas'): a fit outside it is data the model cannot follow, said in `problems`, not written.
struct Setter {
  std::vector<std::string>* problems = nullptr;
  void operator()(YAML::Node node, const std::string& key, const Estimate& e, double low = -INFINITY,
                  double high = INFINITY) const {
    if (!e.ok() || !std::isfinite(e.value)) return;
    if (e.value < low || e.value > high) {
      if (problems) {
        char buf[200];
        std::snprintf(buf, sizeof buf, "%s = %.4g is outside the model's range %g … %g: not written", key.c_str(),
                      e.value, low, high);
        problems->push_back(buf);
      }
      return;
    }
    node[key] = Round4(e.value);
  }
};

// Each camera's own part of the carpet: the bounding box of the points nearer its nadir than any
// other's, over the field and 0.3 m beyond (for cameras on a grid, their cells exactly). m.
std::map<int, Eigen::Vector4d> CameraAreas(const std::map<int, Eigen::Vector3d>& cameras, double length, double width) {
  std::map<int, Eigen::Vector4d> areas;
  const double hx = 0.5 * length + 0.3, hy = 0.5 * width + 0.3, step = 0.02;
  for (double x = -hx; x <= hx + 1e-9; x += step) {
    for (double y = -hy; y <= hy + 1e-9; y += step) {
      int nearest = -1;
      double best = INFINITY;
      for (const auto& [id, p] : cameras) {
        const double d = std::hypot(p.x() - x, p.y() - y);
        if (d < best) best = d, nearest = id;
      }
      auto [it, fresh] = areas.try_emplace(nearest, Eigen::Vector4d(x, y, x, y));
      Eigen::Vector4d& a = it->second;
      a = Eigen::Vector4d(std::min(a[0], x), std::min(a[1], y), std::max(a[2], x), std::max(a[3], y));
    }
  }
  return areas;
}

constexpr int kMinChips = 3;  // fewer chips: their dampings are reported, not written

std::string FileName(const RobotKey& k) {
  return std::string("robot-") + (k.team == TeamColour::kBlue ? "blue-" : "yellow-") + std::to_string(k.id) + ".yaml";
}

const char* TeamName(TeamColour t) { return t == TeamColour::kBlue ? "blue" : "yellow"; }

// The median of the robots' estimates of one quantity (a team's robots are normally alike).
Estimate TeamValue(const std::vector<const RobotFit*>& robots, Estimate RobotFit::*member) {
  std::vector<double> v;
  int samples = 0;
  for (const RobotFit* r : robots) {
    const Estimate& e = r->*member;
    if (e.ok() && std::isfinite(e.value)) v.push_back(e.value), samples += e.samples;
  }
  if (v.empty()) return {};
  std::sort(v.begin(), v.end());
  const double median = v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
  return {median, v.front(), v.back(), samples};
}

// The robot file `base` with the servo limits of `fit`, headed by what they rest on.
void WriteRobot(const fs::path& base, const fs::path& file, const RobotFit& fit, const std::string& who,
                const std::string& source, const Setter& Set) {
  YAML::Node node = Load(base);
  YAML::Node limits = node["drive"]["limits"];
  Set(limits, "max_speed", fit.top_speed, 0, 1e3);
  Set(limits, "max_accel", fit.accel_along, 0, 1e3);
  Set(limits, "max_brake", fit.brake_along, 0, 1e3);
  Set(limits, "max_angular_speed", fit.angular_top_speed, 0, 1e3);
  Set(limits, "max_angular_accel", fit.angular_accel, 0, 1e4);
  Set(limits, "max_angular_brake", fit.angular_brake, 0, 1e4);
  std::ostringstream h;
  h << "SPDX-License-Identifier: Apache-2.0\n"
    << "Fitted by `ubersim calibrate` to " << source << " (" << who << "), over " << base.filename().string()
    << ":\ndrive.limits from the log, 95 % intervals in brackets ([report.md](report.md) for the data):\n"
    << "  max_speed          " << Describe(fit.top_speed, "steps") << " m/s\n"
    << "  max_accel          " << Describe(fit.accel_along, "ramps") << " m/s² (along the heading)\n"
    << "  max_brake          " << Describe(fit.brake_along, "ramps") << " m/s² (along the heading)\n"
    << "  max_angular_speed  " << Describe(fit.angular_top_speed, "steps") << " rad/s\n"
    << "  max_angular_accel  " << Describe(fit.angular_accel, "ramps") << " rad/s²\n"
    << "  max_angular_brake  " << Describe(fit.angular_brake, "ramps") << " rad/s²\n"
    << "Across the heading (the servo's limits are one for every direction; the drive's wheels make\n"
    << "the difference): speed-up " << Describe(fit.accel_across, "ramps") << " m/s², braking "
    << Describe(fit.brake_across, "ramps") << " m/s².\n";
  if (fit.response_delay.ok()) {
    h << "Command to motion: " << Describe(fit.response_delay, "steps") << " s (latency + wheel lag; the world's\n"
      << "radio.latency).\n";
  }
  Write(file, Comment(h.str()), node);
}

}  // namespace

Estimate RollingFriction(const Estimate& acc_roll, double k, double radius) {
  if (!acc_roll.ok()) return {};
  const double f = (1 + k) * radius / 9.81;
  return {-acc_roll.value * f, -acc_roll.high * f, -acc_roll.low * f, acc_roll.samples};
}

BaseBall ReadBaseBall(const fs::path& base_world) {
  BaseBall b;
  const YAML::Node world = Load(base_world);
  if (!world["ball"] || !world["ball"].IsScalar()) return b;
  fs::path file(world["ball"].as<std::string>());
  if (file.is_relative()) file = fs::absolute(base_world).parent_path() / file;
  const YAML::Node ball = Load(file);
  if (ball["inertia_factor"]) b.inertia_factor = ball["inertia_factor"].as<double>();
  if (ball["radius"]) b.radius = ball["radius"].as<double>();
  return b;
}

std::string Describe(const Estimate& e, const char* what_samples) {
  if (!e.ok() || !std::isfinite(e.value)) return "not estimated";
  char buf[160];
  std::snprintf(buf, sizeof buf, "%.4g [%.4g, %.4g] (%d %s)", e.value, e.low, e.high, e.samples, what_samples);
  return buf;
}

ModelFiles WriteModelFiles(const fs::path& base_world, const fs::path& out_dir, const CalibrationFits& fits,
                           bool geometry_models, std::vector<std::string>* problems) {
  const Setter Set{problems};
  fs::create_directories(out_dir);
  const fs::path out = fs::absolute(out_dir).lexically_normal();
  const fs::path base_dir = fs::absolute(base_world).parent_path();
  ModelFiles files;
  files.world = out / "world.yaml";
  YAML::Node world = Load(base_world);

  // Paths the base names, made to work from the output folder.
  for (const char* key : {"field", "ball"}) {
    if (world[key] && world[key].IsScalar()) world[key] = Rebased(world[key].as<std::string>(), base_dir, out);
  }
  if (world["fields"] && world["fields"].IsSequence()) {
    for (std::size_t i = 0; i < world["fields"].size(); ++i) {
      world["fields"][i] = Rebased(world["fields"][i].as<std::string>(), base_dir, out);
    }
  }
  if (world["plugin_paths"] && world["plugin_paths"].IsSequence()) {
    for (std::size_t i = 0; i < world["plugin_paths"].size(); ++i) {
      world["plugin_paths"][i] = Rebased(world["plugin_paths"][i].as<std::string>(), base_dir, out);
    }
  }
  const auto team_model = [&](const char* team) -> std::string {
    if (world["teams"] && world["teams"][team] && world["teams"][team]["model"]) {
      return world["teams"][team]["model"].as<std::string>();
    }
    return {};
  };
  if (world["teams"]) {
    for (const char* team : {"blue", "yellow"}) {
      if (world["teams"][team] && world["teams"][team]["model"]) {
        world["teams"][team]["model"] = Rebased(team_model(team), base_dir, out);
      }
    }
  }
  if (world["robots"] && world["robots"].IsSequence()) {
    for (auto entry : world["robots"]) {
      if (entry["model"]) entry["model"] = Rebased(entry["model"].as<std::string>(), base_dir, out);
    }
  }

  // The ball: its own file and the world's ball–carpet contact, which is what the carpet uses.
  std::ostringstream header;
  header << "SPDX-License-Identifier: Apache-2.0\nWorld fitted by `ubersim calibrate` to " << fits.source
         << ", over " << base_world.filename().string() << ".\nWhat was fitted and from which data: report.md.\n";
  if (fits.ball.enough_data && world["ball"]) {
    const fs::path ball_base = out / world["ball"].as<std::string>();
    YAML::Node ball = Load(ball_base);
    // The ball's inertia is the ball's (a golf ball's is known): it stays, and the rolling
    // resistance that gives the fitted rolling deceleration follows from it. The switch fraction
    // is not a contact parameter: spin-free it is 1/(1 + k), and what a kick's spin adds comes
    // from the kicker and the dribbler as it does on the field (the report compares the two).
    const double k = ball["inertia_factor"] ? ball["inertia_factor"].as<double>() : 0.4;
    const double radius = ball["radius"] ? ball["radius"].as<double>() : 0.0215;
    const Estimate rho = RollingFriction(fits.ball.acc_roll, k, radius);
    Set(ball["surface"], "mu", fits.ball.mu, 0, 1000);
    Set(ball["surface"], "rolling_friction", rho, 0, 0.1);
    // Chips: written from three on (one chip's dampings are one bounce's, not the ball's).
    const Estimate bounce = fits.ball.damping_z.samples >= kMinChips ? fits.ball.damping_z : Estimate{};
    Set(ball["surface"], "bounce", bounce, 0, 1);
    std::ostringstream h;
    h << "SPDX-License-Identifier: Apache-2.0\nFitted by `ubersim calibrate` to " << fits.source << ", over "
      << ball_base.filename().string() << " (" << fits.ball.runs.size() << " candidate runs; report.md).\n"
      << "The league's two-phase model, 95 % intervals:\n"
      << "  acc_slide  " << Describe(fits.ball.acc_slide, "runs") << " m/s²\n"
      << "  acc_roll   " << Describe(fits.ball.acc_roll, "runs") << " m/s²\n"
      << "  k_switch   " << Describe(fits.ball.k_switch, "runs") << "\n"
      << "give the contact parameters below (surface.mu = −acc_slide/g; surface.rolling_friction =\n"
      << "−acc_roll·(1 + inertia_factor)·radius/g with this ball's inertia_factor " << k << "):\n"
      << "  mu               " << Describe(fits.ball.mu, "runs") << "\n"
      << "  rolling_friction " << Describe(rho, "runs") << " m\n"
      << "A spin-free ball of this inertia turns from sliding to rolling at " << Round4(1 / (1 + k))
      << " of its speed;\nthe kicks in the log switched at " << Describe(fits.ball.k_switch, "runs")
      << ": the rest is the spin the kicks gave.\n"
      << "Chips: damping_z (surface.bounce) " << Describe(fits.ball.damping_z, "chips") << ", horizontal "
      << Describe(fits.ball.damping_xy_first_hop, "chips") << " at the first hop, "
      << Describe(fits.ball.damping_xy_other_hops, "chips") << " later (the geometry's chip model).\n";
    files.ball = out / "ball.yaml";
    Write(files.ball, Comment(h.str()), ball);
    world["ball"] = "ball.yaml";
    if (world["materials"] && world["materials"].IsSequence()) {
      for (auto m : world["materials"]) {
        if (!m["between"] || !m["between"].IsSequence() || m["between"].size() != 2) continue;
        const std::string a = m["between"][0].as<std::string>(), b = m["between"][1].as<std::string>();
        if ((a == "ball" && b == "carpet") || (a == "carpet" && b == "ball")) {
          Set(m, "mu", fits.ball.mu, 0, 1000);
          Set(m, "rolling_friction", RollingFriction(fits.ball.acc_roll, k, radius), 0, 0.1);
          Set(m, "bounce", bounce, 0, 1);
        }
      }
    }
    header << "ball: ball.yaml, and the ball–carpet contact in materials, from the ball fit.\n";
  }

  // Robots: a file per robot fitted, and per team the median of its robots for the others.
  std::map<TeamColour, std::vector<const RobotFit*>> by_team;
  for (const RobotFit& r : fits.robots) {
    if (r.enough_data) by_team[r.robot.team].push_back(&r);
  }
  std::map<TeamColour, std::string> team_files;
  for (const auto& [team, robots] : by_team) {
    const std::string base = team_model(TeamName(team));
    if (base.empty()) continue;
    RobotFit median;
    median.robot = {team, -1};
    for (auto member : {&RobotFit::top_speed, &RobotFit::accel_along, &RobotFit::brake_along, &RobotFit::accel_across,
                        &RobotFit::brake_across, &RobotFit::angular_top_speed, &RobotFit::angular_accel,
                        &RobotFit::angular_brake, &RobotFit::latency, &RobotFit::response_delay}) {
      median.*member = TeamValue(robots, member);
    }
    const std::string name = std::string("robot-") + TeamName(team) + ".yaml";
    WriteRobot(out / world["teams"][TeamName(team)]["model"].as<std::string>(), out / name, median,
               std::string("the median of ") + std::to_string(robots.size()) + " " + TeamName(team) +
                   " robots; the ranges are the robots' lowest and highest",
               fits.source, Set);
    team_files[team] = name;
    world["teams"][TeamName(team)]["model"] = name;
  }
  if (world["robots"] && world["robots"].IsSequence()) {
    for (auto entry : world["robots"]) {
      if (!entry["team"] || !entry["id"] || !entry["model"]) continue;
      const std::string team = entry["team"].as<std::string>();
      const RobotKey key{team == "yellow" ? TeamColour::kYellow : TeamColour::kBlue, entry["id"].as<int>()};
      const auto fit = std::find_if(fits.robots.begin(), fits.robots.end(),
                                    [&](const RobotFit& r) { return r.robot == key && r.enough_data; });
      if (fit != fits.robots.end()) {
        const fs::path file = out / FileName(key);
        WriteRobot(out / entry["model"].as<std::string>(), file, *fit, RobotName(key), fits.source, Set);
        files.robots[key] = file;
        entry["model"] = FileName(key);
      } else if (team_files.count(key.team)) {
        entry["model"] = team_files[key.team];
      }
    }
  }
  if (!by_team.empty()) header << "Robot models: the robot-*.yaml files beside this one, from the robot fit.\n";

  // The vision system and the radio.
  if (fits.cameras.enough_data) {
    YAML::Node perception = world["perception"];
    for (const auto& [key, value] : fits.perception.keys) {
      // ÜberSim stamps t_capture as t_sent − processing_time: a processing time below the latency
      // would stamp captures later than they were. ssl-vision's stamps are true, so the field's
      // receive − capture is the world's latency and the stamps stay true (processing_time unset;
      // the report gives the field's t_sent − t_capture).
      if (key == "processing_time") continue;
      const std::size_t dot = key.find('.');
      if (dot == std::string::npos) {
        perception[key] = Round4(value);
      } else {
        perception[key.substr(0, dot)][key.substr(dot + 1)] = Round4(value);
      }
    }
    perception["unsynchronised_cameras"] = fits.perception.unsynchronised_cameras;
    // The cameras as the log's geometry has them, each over its own part of the carpet.
    if (!fits.camera_positions.empty() && fits.field_length > 0 && fits.field_width > 0) {
      perception.remove("camera_count");
      perception.remove("camera_height");
      YAML::Node list(YAML::NodeType::Sequence);
      for (const auto& [id, area] : CameraAreas(fits.camera_positions, fits.field_length, fits.field_width)) {
        const Eigen::Vector3d& p = fits.camera_positions.at(id);
        YAML::Node c;
        c.SetStyle(YAML::EmitterStyle::Flow);
        c["id"] = id;
        for (double v : {p.x(), p.y(), p.z()}) c["position"].push_back(Millimetres(v));
        for (int i = 0; i < 4; ++i) c["area"].push_back(Millimetres(area[i]));
        list.push_back(c);
      }
      perception["cameras"] = list;
    }
    header << "perception: from the camera fit (report.md, Cameras); cameras and keys not fitted as the base has them.\n";
  }
  if (fits.latency.ok()) {
    world["radio"]["latency"] = Round4(std::max(0.0, fits.latency.value));
    header << "radio.latency: the robots' command-to-motion delay (latency + wheel lag), " << Describe(fits.latency, "steps")
           << " s;\nÜberSim's drives add their own few ms of lag on top.\n";
  }
  if (geometry_models && fits.ball.enough_data && world["transports"] && world["transports"].IsSequence()) {
    for (auto t : world["transports"]) {
      if (!t["plugin"] || t["plugin"].as<std::string>() != "ssl_vision") continue;
      YAML::Node straight = t["ball_model"]["straight_two_phase"];
      Set(straight, "acc_slide", fits.ball.acc_slide, -100, 0);
      Set(straight, "acc_roll", fits.ball.acc_roll, -100, 0);
      Set(straight, "k_switch", fits.ball.k_switch, 0, 1);
      if (fits.ball.damping_z.samples >= kMinChips) {
        YAML::Node chip = t["ball_model"]["chip_fixed_loss"];
        Set(chip, "damping_xy_first_hop", fits.ball.damping_xy_first_hop, 0, 1);
        Set(chip, "damping_xy_other_hops", fits.ball.damping_xy_other_hops, 0, 1);
        Set(chip, "damping_z", fits.ball.damping_z, 0, 1);
      }
    }
    header << "The ssl_vision transport announces the fitted ball models in the geometry (SSL_GeometryModels).\n";
  }
  if (world["name"]) world["name"] = world["name"].as<std::string>() + "-calibrated";
  Write(files.world, Comment(header.str()), world);
  return files;
}

}  // namespace ubersim::calibrate
