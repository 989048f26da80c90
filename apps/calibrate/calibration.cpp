// SPDX-License-Identifier: Apache-2.0
#include "calibration.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <future>
#include <sstream>
#include <stdexcept>

#include "camera_fit.hpp"
#include "check_run.hpp"
#include "robot_fit.hpp"
#include "ubersim/validation/svg_plot.hpp"

namespace ubersim::calibrate {
namespace fs = std::filesystem;
namespace {

double Since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::string Row(const std::string& what, const Estimate& e, const char* unit, const char* samples, const std::string& key) {
  char buf[320];
  if (!e.ok() || !std::isfinite(e.value)) {
    std::snprintf(buf, sizeof buf, "| %s | not estimated | | | %s |\n", what.c_str(), key.c_str());
  } else {
    std::snprintf(buf, sizeof buf, "| %s | %.4g %s | %.4g … %.4g | %d %s | %s |\n", what.c_str(), e.value, unit, e.low,
                  e.high, e.samples, samples, key.c_str());
  }
  return buf;
}

// Command to motion over the robots (latency + wheel lag, the robust sum): the median of theirs,
// the range their intervals span.
Estimate CombinedLatency(const std::vector<RobotFit>& robots) {
  std::vector<double> v;
  int samples = 0;
  double low = INFINITY, high = -INFINITY;
  for (const RobotFit& r : robots) {
    if (!r.enough_data || !r.response_delay.ok()) continue;
    v.push_back(r.response_delay.value);
    samples += r.response_delay.samples;
    low = std::min(low, r.response_delay.low);
    high = std::max(high, r.response_delay.high);
  }
  if (v.empty()) return {};
  std::sort(v.begin(), v.end());
  return {v[v.size() / 2], low, high, samples};
}

std::string LogSummary(const LogSession& s, const SessionTracks& tracks) {
  std::ostringstream o;
  std::map<int, int> per_camera;
  for (const auto& f : s.frames) ++per_camera[f.camera_id];
  o << "| | |\n|---|---|\n";
  o << "| files | ";
  for (std::size_t i = 0; i < s.paths.size(); ++i) o << (i ? ", " : "") << "`" << fs::path(s.paths[i]).filename().string() << "`";
  char buf[200];
  std::snprintf(buf, sizeof buf, " |\n| duration | %.1f s |\n", s.duration());
  o << buf;
  o << "| records | " << s.counts.records << " (" << s.counts.detection_frames << " camera frames, "
    << s.counts.geometry_packets << " geometry packets, " << s.counts.command_records << " command records, "
    << s.counts.other_records << " others not used) |\n";
  o << "| cameras | ";
  bool first = true;
  for (const auto& [id, n] : per_camera) {
    o << (first ? "" : ", ") << id << " (" << n << " frames";
    if (s.cameras.count(id)) {
      const auto& p = s.cameras.at(id);
      std::snprintf(buf, sizeof buf, ", at %.2f, %.2f, %.2f m", p.x(), p.y(), p.z());
      o << buf;
    }
    o << ")";
    first = false;
  }
  o << " |\n";
  o << "| ball | " << tracks.ball.size() << " detections on the ball's track, " << tracks.false_balls
    << " elsewhere (false or short-lived) |\n";
  o << "| robots | " << tracks.robots.size() << " seen";
  if (!s.commands.empty()) o << ", " << s.commands.size() << " with commands";
  o << " |\n";
  if (s.counts.duplicate_frames) o << "| duplicates | " << s.counts.duplicate_frames << " camera frames recorded twice, dropped |\n";
  if (s.counts.undecodable) {
    o << "| undecodable | " << s.counts.undecodable << " payloads skipped, the first at " << s.counts.first_undecodable << " |\n";
  }
  return o.str();
}

void WriteSection(std::ostream& md, const fs::path& dir, const ReportSection& section) {
  md << section.markdown << "\n";
  for (const auto& p : section.plots) {
    std::ofstream f(dir / p.file);
    f << validation::RenderSvg(p);
    if (!f) throw std::runtime_error("cannot write " + (dir / p.file).string());
  }
}

// The tracks the fits saw, as CSV (SI units, session clock): to look at them with other tools.
void DumpTracks(const fs::path& dir, const LogSession& session, const SessionTracks& tracks,
                const std::vector<RobotFitInput>& robots) {
  fs::create_directories(dir);
  const auto open = [&](const std::string& name, const char* header) {
    std::ofstream f(dir / name);
    f.precision(9);
    f << header << "\n";
    return f;
  };
  {
    auto f = open("ball.csv", "t,x,y,camera");
    for (const auto& p : tracks.ball) f << p.t << "," << p.x << "," << p.y << "," << p.camera_id << "\n";
  }
  {
    auto f = open("cameras.csv", "camera,x,y,z");
    for (const auto& [id, p] : session.cameras) f << id << "," << p.x() << "," << p.y() << "," << p.z() << "\n";
  }
  for (const auto& r : robots) {
    const std::string name = std::string(r.robot.team == TeamColour::kBlue ? "blue-" : "yellow-") + std::to_string(r.robot.id);
    auto f = open("robot-" + name + ".csv", "t,x,y,yaw,camera");
    for (const auto& p : r.track) f << p.t << "," << p.x << "," << p.y << "," << p.yaw << "," << p.camera_id << "\n";
    if (r.commands.empty()) continue;
    auto c = open("commands-" + name + ".csv", "t,forward,left,angular,kick_speed,kick_angle,dribbler_speed");
    for (const auto& s : r.commands) {
      c << s.t << "," << s.forward << "," << s.left << "," << s.angular << "," << s.kick_speed << "," << s.kick_angle
        << "," << s.dribbler_speed << "\n";
    }
  }
}

}  // namespace

CalibrationOutcome Calibrate(const CalibrateOptions& options, const std::function<void(const std::string&)>& progress) {
  CalibrationOutcome outcome;
  auto t0 = std::chrono::steady_clock::now();
  const LogSession session = ReadLogSession(options.logs);
  const SessionTracks tracks = BuildTracks(session);
  outcome.seconds_reading = Since(t0);
  {
    char buf[200];
    std::snprintf(buf, sizeof buf, "read %lld camera frames (%.1f s of play) in %.2f s",
                  static_cast<long long>(session.frames.size()), session.duration(), outcome.seconds_reading);
    progress(buf);
  }
  t0 = std::chrono::steady_clock::now();
  CalibrationFits& fits = outcome.fits;
  for (const auto& p : options.logs) fits.source += (fits.source.empty() ? "" : ", ") + fs::path(p).filename().string();

  // The three fits are independent: ball and cameras beside the robots, on the machine's cores.
  BallFitInput ball_input;
  ball_input.ball = tracks.ball;
  ball_input.robot_distance = [&tracks](double t, double x, double y) { return tracks.NearestRobot(t, x, y); };
  ball_input.cameras = session.cameras;
  ball_input.source = fits.source;
  auto ball_future = std::async(std::launch::async, [&] {
    const auto start = std::chrono::steady_clock::now();
    BallFit fit = FitBall(ball_input, options.ball);
    outcome.seconds_ball = Since(start);
    return fit;
  });

  CameraFitInput camera_input;
  camera_input.frames = &session.frames;
  camera_input.ball = tracks.ball;
  camera_input.robots = tracks.robots;
  camera_input.cameras = session.cameras;
  auto camera_future = std::async(std::launch::async, [&] {
    const auto start = std::chrono::steady_clock::now();
    CameraFit fit = FitCameras(camera_input);
    outcome.seconds_cameras = Since(start);
    return fit;
  });

  std::vector<RobotFitInput> robot_inputs;
  for (const auto& [key, track] : tracks.robots) {
    RobotFitInput in;
    in.robot = key;
    in.track = track;
    in.commands = LocalCommands(session, tracks, key);
    robot_inputs.push_back(std::move(in));
  }
  if (options.dump_tracks) DumpTracks(options.out_dir / "tracks", session, tracks, robot_inputs);
  const auto robots_start = std::chrono::steady_clock::now();
  for (const auto& in : robot_inputs) fits.robots.push_back(FitRobot(in));
  outcome.seconds_robots = Since(robots_start);
  fits.ball = ball_future.get();
  // The ball keeps its own inertia (the model files do): the rolling resistance follows from it,
  // and the switch the kicks showed is theirs, not the ball's (model_output.cpp says why).
  const BaseBall base_ball = ReadBaseBall(options.base_world);
  fits.ball.rolling_friction = RollingFriction(fits.ball.acc_roll, base_ball.inertia_factor, base_ball.radius);
  fits.ball.inertia_factor = {};
  fits.cameras = camera_future.get();
  fits.perception = PerceptionFromFit(fits.cameras);
  fits.latency = CombinedLatency(fits.robots);
  fits.camera_positions = session.cameras;
  if (session.field) {
    fits.field_length = session.field->length;
    fits.field_width = session.field->width;
  }
  outcome.seconds_fitting = Since(t0);
  {
    int robots_fitted = 0;
    for (const auto& r : fits.robots) robots_fitted += r.enough_data ? 1 : 0;
    char buf[240];
    std::snprintf(buf, sizeof buf,
                  "fitted in %.2f s (ball %.2f s, robots %.2f s, cameras %.2f s, side by side): ball %s, %d of %zu "
                  "robots, cameras %s",
                  outcome.seconds_fitting, outcome.seconds_ball, outcome.seconds_robots, outcome.seconds_cameras,
                  fits.ball.enough_data ? "yes" : "no (too little data)", robots_fitted, fits.robots.size(),
                  fits.cameras.enough_data ? "yes" : "no (too little data)");
    progress(buf);
    outcome.anything_fitted = fits.ball.enough_data || robots_fitted > 0 || fits.cameras.enough_data;
  }
  for (const auto& p : fits.ball.problems) outcome.problems.push_back("ball: " + p);
  for (const auto& r : fits.robots) {
    for (const auto& p : r.problems) outcome.problems.push_back(RobotName(r.robot) + ": " + p);
  }
  for (const auto& p : fits.cameras.problems) outcome.problems.push_back("cameras: " + p);

  fs::create_directories(options.out_dir);
  if (outcome.anything_fitted) {
    std::vector<std::string> unwritten;
    outcome.files = WriteModelFiles(options.base_world, options.out_dir, fits, options.geometry_models, &unwritten);
    for (const auto& u : unwritten) outcome.problems.push_back("model files: " + u);
  }

  // The report.
  outcome.report = options.out_dir / "report.md";
  std::ofstream md(outcome.report);
  md << "# Calibration: " << fits.source << "\n\n"
     << "Written by `ubersim calibrate` over `" << options.base_world.filename().string()
     << "`. Every value with its 95 % interval and the data it rests on; the plots show each fit over the log's "
        "data. How to read it: [docs/calibrate.md](https://github.com/ubersim/ubersim/blob/main/docs/calibrate.md).\n\n";
  md << "## The log\n\n" << LogSummary(session, tracks) << "\n";
  md << "## Summary\n\n| quantity | fitted | 95 % interval | data | model key |\n|---|---|---|---|---|\n";
  const BallFit& b = fits.ball;
  md << Row("ball: sliding deceleration", b.acc_slide, "m/s²", "runs", "geometry `acc_slide`");
  md << Row("ball: rolling deceleration", b.acc_roll, "m/s²", "runs", "geometry `acc_roll`");
  md << Row("ball: slide→roll switch", b.k_switch, "", "runs", "geometry `k_switch`");
  md << Row("ball–carpet friction μ", b.mu, "", "runs", "ball–carpet `mu`");
  md << Row("ball rolling resistance ρ", b.rolling_friction, "m", "runs", "ball–carpet `rolling_friction`");
  {
    char buf[240];
    std::snprintf(buf, sizeof buf,
                  "| ball inertia factor | %.4g (the ball's own, kept) | | | ball `inertia_factor`: spin-free, the "
                  "switch would be %.3f |\n",
                  base_ball.inertia_factor, 1 / (1 + base_ball.inertia_factor));
    md << buf;
  }
  md << Row("chip: vertical damping", b.damping_z, "", "chips", "ball–carpet `bounce`, geometry `damping_z`");
  md << Row("chip: horizontal, first hop", b.damping_xy_first_hop, "", "chips", "geometry `damping_xy_first_hop`");
  md << Row("chip: horizontal, later hops", b.damping_xy_other_hops, "", "chips", "geometry `damping_xy_other_hops`");
  for (const RobotFit& r : fits.robots) {
    if (!r.enough_data) continue;
    const std::string n = RobotName(r.robot);
    md << Row(n + ": top speed", r.top_speed, "m/s", "steps", "`drive.limits.max_speed`");
    md << Row(n + ": acceleration along", r.accel_along, "m/s²", "ramps", "`max_accel`");
    md << Row(n + ": braking along", r.brake_along, "m/s²", "ramps", "`max_brake`");
    md << Row(n + ": acceleration across", r.accel_across, "m/s²", "ramps", "(comment)");
    md << Row(n + ": braking across", r.brake_across, "m/s²", "ramps", "(comment)");
    md << Row(n + ": top turn rate", r.angular_top_speed, "rad/s", "steps", "`max_angular_speed`");
    md << Row(n + ": angular acceleration", r.angular_accel, "rad/s²", "ramps", "`max_angular_accel`");
    md << Row(n + ": angular braking", r.angular_brake, "rad/s²", "ramps", "`max_angular_brake`");
    md << Row(n + ": command → setpoint (latency)", r.latency, "s", "steps", "");
    md << Row(n + ": command → motion (latency + lag)", r.response_delay, "s", "steps", "`radio.latency`");
  }
  for (const auto& [key, value] : fits.perception.keys) {
    char buf[200];
    std::snprintf(buf, sizeof buf, "| vision `%s` | %.4g | per camera below | | `perception.%s` |\n", key.c_str(), value,
                  key.c_str());
    md << buf;
  }
  md << "\n";
  if (!outcome.problems.empty()) {
    md << "### Not fitted, and why\n\n";
    for (const auto& p : outcome.problems) md << "- " << p << "\n";
    md << "\n";
  }
  md << "## Ball\n\n";
  WriteSection(md, options.out_dir, BallReport(fits.ball, ball_input));
  md << "## Robots\n\n";
  for (std::size_t i = 0; i < fits.robots.size(); ++i) WriteSection(md, options.out_dir, RobotReport(fits.robots[i], robot_inputs[i]));
  md << "## Cameras\n\n";
  WriteSection(md, options.out_dir, CameraReport(fits.cameras));
  if (options.check && outcome.anything_fitted) {
    progress("checking: the fitted world through the log's manoeuvres");
    CheckInput check;
    check.world = outcome.files.world;
    check.plugin_paths = options.plugin_paths;
    check.session = &session;
    check.tracks = &tracks;
    check.fits = &fits;
    check.robot_inputs = &robot_inputs;
    md << "## Check: the fitted world against the log\n\n";
    WriteSection(md, options.out_dir, RunCheck(check));
  }
  md << "## Files\n\n";
  if (!outcome.anything_fitted) {
    md << "None: nothing had enough data to fit (above).\n";
  } else {
    md << "- `world.yaml`: the world to run (`ubersim run " << (options.out_dir / "world.yaml").string() << "`)\n";
    if (!outcome.files.ball.empty()) md << "- `ball.yaml`: the fitted ball\n";
    for (const auto& [key, file] : outcome.files.robots) md << "- `" << file.filename().string() << "`: " << RobotName(key) << "\n";
  }
  if (!md) throw std::runtime_error("cannot write " + outcome.report.string());
  return outcome;
}

}  // namespace ubersim::calibrate
