// SPDX-License-Identifier: Apache-2.0
// `ubersim soak [WORLD]`: a long headless run under random play and teleports, its state checked
// every simulated second.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "ubersim/kernel/logging.hpp"
#include "ubersim/kernel/state_check.hpp"
#include "ubersim/kernel/world.hpp"
#include "bench.hpp"
#include "command_line.hpp"
#include "commands.hpp"
#include "exit_codes.hpp"
#include "progress.hpp"
#include "soak.hpp"
#include "world_loading.hpp"

namespace ubersim::cli {
namespace {

namespace po = boost::program_options;
namespace bench = kernel::bench;
namespace soak = kernel::soak;

// --log-teleports: one line per teleport, among the findings on stdout.
void PrintTeleport(double t, const char* what, const PositionEvent& e) {
  const std::string who = e.target.is_ball ? std::string("ball")
                                           : std::string(e.target.robot.team == Team::kBlue ? "robot blue "
                                                                                              : "robot yellow ") +
                                                 std::to_string(e.target.robot.id);
  const Vec3 p = e.position.value_or(Vec3::Constant(NAN));
  const Vec3 v = e.velocity.value_or(Vec3::Zero());
  std::printf("t = %.3f s: teleport (%s): %s to (%.3f, %.3f, %.3f) m, yaw %.3f rad, velocity (%.2f, %.2f, %.2f) m/s\n", t,
              what, who.c_str(), p.x(), p.y(), p.z(), e.yaw.value_or(0.0), v.x(), v.y(), v.z());
}

// What --trace follows: the ball, or a robot ("blue 3", "robot yellow 10").
struct TraceTarget {
  bool ball = false;
  RobotId robot;
};

std::optional<TraceTarget> ParseTraceTarget(std::string text) {
  if (text == "ball") return TraceTarget{true, {}};
  if (text.rfind("robot ", 0) == 0) text = text.substr(6);
  const std::size_t space = text.find(' ');
  if (space == std::string::npos) return std::nullopt;
  const std::string team = text.substr(0, space), id = text.substr(space + 1);
  if ((team != "blue" && team != "yellow") || id.empty() || id.size() > 2 ||
      !std::all_of(id.begin(), id.end(), [](char c) { return c >= '0' && c <= '9'; })) {
    return std::nullopt;
  }
  return TraceTarget{false, {team == "blue" ? Team::kBlue : Team::kYellow, std::stoi(id)}};
}

// --trace: one line a step for the traced object between the two times, with the nearest robot
// and the ball, to follow a finding step by step from its seed.
void PrintTrace(const kernel::World& world, const TraceTarget& target) {
  const WorldSnapshot s = world.GroundTruth();
  const double t = world.clock().seconds();
  const BallState& ball = s.ball;
  if (target.ball) {
    const Vec3 p = ball.pose.position, v = ball.twist.linear;
    std::printf("t = %.3f s: trace ball: position (%.4f, %.4f, %.4f) m, velocity (%.3f, %.3f, %.3f) m/s\n", t, p.x(),
                p.y(), p.z(), v.x(), v.y(), v.z());
    return;
  }
  const auto it = std::find_if(s.robots.begin(), s.robots.end(), [&](const RobotState& r) { return r.id == target.robot; });
  if (it == s.robots.end() || !it->present) return;
  const RobotState& r = *it;
  const Vec3 p = r.pose.position, v = r.twist.linear, w = r.twist.angular;
  const double lean = std::acos(std::clamp((r.pose.orientation * Vec3::UnitZ()).z(), -1.0, 1.0));
  const RobotState* nearest = nullptr;
  double apart = INFINITY;
  for (const RobotState& q : s.robots) {
    if (&q == &r || !q.present) continue;
    const double d = (q.pose.position - p).head<2>().norm();
    if (d < apart) apart = d, nearest = &q;
  }
  std::printf("t = %.3f s: trace robot %s %d: position (%.4f, %.4f, %.4f) m, yaw %.3f rad, lean %.1f°, velocity "
              "(%.3f, %.3f, %.3f) m/s, angular (%.2f, %.2f, %.2f) rad/s",
              t, ToString(r.id.team), r.id.id, p.x(), p.y(), p.z(), r.pose.Yaw(), lean * 180.0 / M_PI, v.x(), v.y(),
              v.z(), w.x(), w.y(), w.z());
  if (nearest) std::printf(", nearest robot %s %d %.3f m apart", ToString(nearest->id.team), nearest->id.id, apart);
  std::printf(", ball %.3f m apart", (ball.pose.position - p).norm());
  // What the traced robot is inside, however shallow: a push's depth building up step by step.
  kernel::StateCheckOptions overlaps;
  overlaps.finite = overlaps.speed = overlaps.carpet = overlaps.walls = overlaps.tilt = false;
  overlaps.limits.robot_penetration = overlaps.limits.ball_penetration = 0.0005;
  const auto is_traced = [&](const kernel::StateObject& o) {
    return o.kind == kernel::StateObject::Kind::kRobot && o.robot == target.robot;
  };
  for (const kernel::StateViolation& v : kernel::CheckState(world, overlaps)) {
    if (!v.other || (!is_traced(v.object) && !is_traced(*v.other))) continue;
    const kernel::StateObject& them = is_traced(v.object) ? *v.other : v.object;
    std::printf(", %.1f mm inside %s", 1e3 * v.value, them.name.c_str());
  }
  std::printf("\n");
}

// The progress line's text: simulated and wall time, real-time factor, memory, findings so far.
std::string SoakProgressText(const soak::SoakProgress& p) {
  char line[200];
  std::snprintf(line, sizeof line, "sim %7.0f / %.0f s | wall %7.1f s | %5.2f× real time | %6.1f MB | %lld findings",
                p.sim_time, p.sim_seconds, p.wall_seconds, p.sim_time / std::max(p.wall_seconds, 1e-9), p.rss_mb,
                static_cast<long long>(p.findings));
  return line;
}

}  // namespace

int SoakCommand(const std::vector<std::string>& args) {
  po::options_description desc(
      "usage: ubersim soak [WORLD] [options]\n\n"
      "Runs WORLD (a file or a shipped world's name; default div-a) headless and as fast as\n"
      "possible for --duration simulated seconds under seeded random play and random teleports\n"
      "(robots and the ball onto other robots, into walls and goals, at up to 3 m/s and 6.5 m/s),\n"
      "and checks the state every simulated second (--check-period): no NaN or infinite value,\n"
      "nothing outside the walls or under the carpet, no robot inside another or tipped over,\n"
      "nothing impossibly fast; and the resident memory stays flat after a warm-up. Prints each\n"
      "finding with its simulated time, progress, and a summary. Exit code 6 on any finding or\n"
      "memory growth of 5 % or more.\n\noptions");
  double duration = 3600.0, interval = 0.5, wall_overlap = 0.5, check_period = 1.0, trace_from = 0.0,
         trace_to = INFINITY;
  std::string trace;
  std::uint64_t seed = 1;
  PhysicsFlags physics_flags;
  std::string world_arg = "div-a", robot;
  std::vector<std::string> plugin_paths;
  desc.add_options()("help,h", "this help")
      ("duration", po::value<double>(&duration)->default_value(duration), "simulated seconds")
      ("seed", po::value<std::uint64_t>(&seed)->default_value(seed), "seed of the random play and the teleports")
      ("teleport-interval", po::value<double>(&interval)->default_value(interval), "mean simulated seconds between teleports")
      ("wall-overlap", po::value<double>(&wall_overlap)->default_value(wall_overlap),
       "how far into a wall a robot is teleported, as a share of the wall's thickness (0..1)")
      ("check-period", po::value<double>(&check_period)->default_value(check_period),
       "simulated seconds between state checks (0: every step, which finds what a check a second misses)")
      ("robot", po::value<std::string>(&robot), "put this robot model file in every robot's place")
      ("quiet,q", "no progress lines")
      ("log-teleports", "print every teleport with its simulated time (to chase a finding)")
      ("trace", po::value<std::string>(&trace),
       "print the state of this object every step (\"ball\", \"blue 3\", \"yellow 10\") between "
       "--trace-from and --trace-to")
      ("trace-from", po::value<double>(&trace_from), "simulated second the trace starts at (default 0)")
      ("trace-to", po::value<double>(&trace_to), "simulated second the trace ends at (default: the end)")
      ("plugin-path", po::value<std::vector<std::string>>(&plugin_paths), "also search DIR for plugins (repeatable)");
  physics_flags.AddTo(desc);
  po::options_description hidden;
  hidden.add_options()("world", po::value<std::string>(&world_arg));
  po::positional_options_description pos;
  pos.add("world", 1);
  po::variables_map vm;
  if (const auto done = ParseCommandLine(args, "soak", desc, vm, &hidden, &pos)) return *done;
  if (!(duration > 0) || !(interval > 0) || !(wall_overlap >= 0 && wall_overlap <= 1) || !(check_period >= 0)) {
    std::cerr << "ubersim soak: --duration and --teleport-interval must be > 0, --wall-overlap 0..1, "
                 "--check-period >= 0\n";
    return kExitUsage;
  }
  std::optional<TraceTarget> trace_target;
  if (vm.count("trace")) {
    trace_target = ParseTraceTarget(trace);
    if (!trace_target) {
      std::cerr << "ubersim soak: --trace takes \"ball\" or a robot as \"blue N\" or \"yellow N\", not \"" << trace
                << "\"\n";
      return kExitUsage;
    }
  }
  kernel::PhysicsOverrides physics;
  if (!physics_flags.Read(vm, "soak", physics)) return kExitUsage;
  const std::filesystem::path file = WorldFileOf(world_arg);
  const WorldLoading loading = LoadingFor({file}, plugin_paths);
  kernel::WorldModel model = bench::LoadTrialWorld(
      loading.loader, file, physics, vm.count("robot") ? std::optional<std::string>(robot) : std::nullopt);
  model.transports.clear();  // headless
  // Plugins' warnings and errors are shown as they come; none is expected.
  kernel::StreamLog log(std::cerr, LogLevel::kWarning);
  kernel::World world(model, *loading.registry, log, /*start_transports=*/false);
  soak::SoakOptions options;
  options.sim_seconds = duration;
  options.seed = seed;
  options.teleport_interval = interval;
  options.wall_overlap = wall_overlap;
  options.check_period = check_period;
  if (vm.count("log-teleports")) options.on_teleport = PrintTeleport;
  if (trace_target) {
    options.after_step = [&](const kernel::World& w) {
      const double t = w.clock().seconds();
      if (t >= trace_from && t <= trace_to) PrintTrace(w, *trace_target);
    };
  }
  std::printf("soak %s (%s): %.0f s simulated, seed %llu, %zu robots, physics %s\n", model.name.c_str(),
              file.string().c_str(), duration, static_cast<unsigned long long>(seed), model.robots.size(),
              DescribePhysics(model.physics).c_str());
  std::fflush(stdout);
  ProgressLine progress(/*shown=*/vm.count("quiet") == 0);
  double next_line = 0;  // off a terminal, one line a simulated minute
  const auto report = soak::RunSoak(
      world, options,
      [&](const soak::SoakProgress& p) {
        if (progress.OnTerminal()) {
          progress.Redraw(SoakProgressText(p));
        } else if (p.sim_time >= next_line) {
          progress.Write(SoakProgressText(p));
          next_line = p.sim_time + 60.0;
        }
      },
      [&](const soak::SoakFinding& f) {
        progress.Clear();
        std::printf("t = %.3f s: %s: %s\n", f.sim_time, ToString(f.violation.issue), f.violation.Describe().c_str());
        std::fflush(stdout);
      });
  progress.Clear();
  std::cout << soak::FormatSummary(report);
  return report.Pass() ? kExitOk : kExitSoakFailed;
}

}  // namespace ubersim::cli
