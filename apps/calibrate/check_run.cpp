// SPDX-License-Identifier: Apache-2.0
#include "check_run.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <numbers>
#include <sstream>

#include "shared/world_loading.hpp"
#include "track_smoothing.hpp"
#include "ubersim/kernel/logging.hpp"
#include "ubersim/kernel/world.hpp"

namespace ubersim::calibrate {
namespace {

// A sample of a trajectory: time from the start, position, heading, world velocity.
struct Sample {
  double t = 0, x = 0, y = 0, yaw = 0, vx = 0, vy = 0, omega = 0;
};

// A world to replay in: the fitted one, headless, every robot off the field to begin with.
class ReplayWorld {
 public:
  ReplayWorld(const CheckInput& in)
      : loaded_(apps::LoadWorldWithPlugins(in.world, in.plugin_paths)), log_(std::cerr, LogLevel::kError) {
    loaded_.model.transports.clear();
    world_ = std::make_unique<kernel::World>(loaded_.model, *loaded_.loading.registry, log_, false);
    for (const RobotState& r : world_->GroundTruth().robots) Place(r.id, false);
    Settle();
  }

  kernel::World& world() { return *world_; }
  /// The fitted world's ball's inertia factor (I = k·m·r²).
  double BallInertia() const { return loaded_.model.ball ? loaded_.model.ball->inertia_factor : 0.4; }
  bool Has(const RobotId& id) const {
    for (const RobotState& r : world_->GroundTruth().robots) {
      if (r.id == id) return true;
    }
    return false;
  }
  void Place(const RobotId& id, bool present, double x = 0, double y = 0, double yaw = 0) {
    PositionEvent e;
    e.target.is_ball = false;
    e.target.robot = id;
    e.present = present;
    if (present) {
      e.position = Vec3(x, y, 0);
      e.yaw = yaw;
      e.velocity = Vec3::Zero();
      e.angular_velocity = Vec3::Zero();
    }
    world_->events().Post(e);
  }
  // The ball at (x, y) moving at (vx, vy) with its surface turning at `spin` m/s the rolling way
  // (spin = speed: rolling without slip, ω = ẑ × v / r, the contact point standing still).
  void Ball(double x, double y, double vx, double vy, double spin, double radius) {
    PositionEvent e;
    e.target.is_ball = true;
    e.position = Vec3(x, y, 0);
    e.velocity = Vec3(vx, vy, 0);
    const double speed = std::hypot(vx, vy);
    const double w = speed > 0 ? spin / (radius * speed) : 0.0;
    e.angular_velocity = Vec3(-vy * w, vx * w, 0);
    world_->events().Post(e);
  }
  void Settle() {
    for (int i = 0; i < 3; ++i) world_->Step();
  }

 private:
  apps::LoadedWorld loaded_;
  kernel::StreamLog log_;
  std::unique_ptr<kernel::World> world_;
};

double Rms(const std::vector<double>& v) {
  if (v.empty()) return NAN;
  double s = 0;
  for (double e : v) s += e * e;
  return std::sqrt(s / static_cast<double>(v.size()));
}

// The commanded steps of a robot: a change from rest to a held command, with the time to the next
// step (or 3 s) after it.
struct StepWindow {
  double t_change = 0;  // s, session clock
  double t_end = 0;
  std::string what;     // "forward 2.20 m/s"
};

std::vector<StepWindow> Steps(const std::vector<CommandSample>& c) {
  std::vector<StepWindow> out;
  const auto still = [](const CommandSample& s) { return std::abs(s.forward) + std::abs(s.left) + std::abs(s.angular) < 1e-3; };
  for (std::size_t i = 1; i < c.size(); ++i) {
    if (!still(c[i - 1]) || still(c[i])) continue;
    // Held for at least 0.5 s.
    std::size_t j = i;
    while (j + 1 < c.size() && std::abs(c[j + 1].forward - c[i].forward) < 1e-3 &&
           std::abs(c[j + 1].left - c[i].left) < 1e-3 && std::abs(c[j + 1].angular - c[i].angular) < 1e-3) {
      ++j;
    }
    if (c[j].t - c[i].t < 0.5) continue;
    // Then the rest until the next change.
    std::size_t k = j + 1;
    while (k + 1 < c.size() && still(c[k + 1])) ++k;
    if (k >= c.size() || !still(c[std::min(k, c.size() - 1)])) continue;
    StepWindow w;
    w.t_change = c[i].t;
    w.t_end = std::min(c[k].t, c[i].t + 3.5);
    char buf[80];
    if (std::abs(c[i].angular) > std::abs(c[i].forward) + std::abs(c[i].left)) {
      std::snprintf(buf, sizeof buf, "turn %.2f rad/s", c[i].angular);
    } else if (std::abs(c[i].forward) >= std::abs(c[i].left)) {
      std::snprintf(buf, sizeof buf, "forward %.2f m/s", c[i].forward);
    } else {
      std::snprintf(buf, sizeof buf, "left %.2f m/s", c[i].left);
    }
    w.what = buf;
    out.push_back(w);
    i = k;
  }
  return out;
}

validation::Series Line(const std::string& label, const std::vector<double>& x, const std::vector<double>& y,
                        bool points = false) {
  validation::Series s;
  s.label = label;
  s.x = x;
  s.y = y;
  s.points = points;
  return s;
}

// Replays one robot step: the robot put where the recording has it just before the command, the
// commands sent at their recorded times; samples every step of the simulation.
std::vector<Sample> ReplayStep(ReplayWorld& rw, const RobotKey& key, const SmoothedTrack& track,
                               const std::vector<CommandSample>& commands, const StepWindow& w, double lead) {
  const RobotId id{key.team == TeamColour::kBlue ? Team::kBlue : Team::kYellow, key.id};
  const auto start = track.At(w.t_change - lead, 0.06);
  if (!start) return {};
  rw.Place(id, true, start->x, start->y, start->yaw);
  rw.Settle();
  kernel::World& world = rw.world();
  const double t0 = world.clock().seconds();
  const double session_t0 = w.t_change - lead;
  auto c = std::lower_bound(commands.begin(), commands.end(), session_t0,
                            [](const CommandSample& s, double t) { return s.t < t; });
  std::vector<Sample> out;
  while (world.clock().seconds() - t0 < w.t_end - session_t0) {
    const double now = session_t0 + world.clock().seconds() - t0;
    while (c != commands.end() && c->t <= now + 1e-9) {
      CommandEvent e;
      e.robot = id;
      e.move = LocalVelocityCommand{c->forward, c->left, c->angular};
      world.events().Post(e);
      ++c;
    }
    world.Step();
    for (const RobotState& r : world.GroundTruth().robots) {
      if (!(r.id == id)) continue;
      out.push_back({world.clock().seconds() - t0, r.pose.position.x(), r.pose.position.y(), r.pose.Yaw(),
                     r.twist.linear.x(), r.twist.linear.y(), r.twist.angular.z()});
    }
  }
  rw.Place(id, false);
  rw.Settle();
  return out;
}

void CheckRobots(const CheckInput& in, ReplayWorld& rw, std::ostringstream& md, std::vector<validation::Plot>& plots) {
  md << "### Robots: each recorded step replayed from its commands\n\n"
        "The robot is put where the recording has it 0.1 s before the command, then given the recorded commands at "
        "their times; its simulated path is compared with the recorded track (smoothed) over the step and the rest "
        "after it. A robot's heading drifting apart during a step (a sideways step turns a real and a simulated "
        "robot differently) shows as a growing error.\n\n| robot | steps | position error RMS | at the end, median | "
        "heading error RMS | worst step (error at its end) |\n|---|---|---|---|---|---|\n";
  // The ball out of the way, in a corner at rest, where it was after the ball's check.
  const auto field = rw.world().GroundTruth().field;
  if (field) rw.Ball(0.5 * field->field_length, 0.5 * field->field_width, 0, 0, 0, 0.0215);
  rw.Settle();
  int robots = 0;
  std::ostringstream images;  // after the table, which an image line would break
  for (const RobotFitInput& r : *in.robot_inputs) {
    if (robots >= in.max_robots || r.commands.empty()) continue;
    const RobotId id{r.robot.team == TeamColour::kBlue ? Team::kBlue : Team::kYellow, r.robot.id};
    if (!rw.Has(id)) continue;
    ++robots;
    const SmoothedTrack track(r.track);
    std::vector<double> errors, heading_errors, end_errors;
    double worst_error = 0;
    std::string worst;
    int replayed = 0;
    for (const StepWindow& w : Steps(r.commands)) {
      if (replayed >= in.max_steps_per_robot) break;
      const double lead = 0.1;
      const std::vector<Sample> sim = ReplayStep(rw, r.robot, track, r.commands, w, lead);
      if (sim.empty()) continue;
      std::vector<double> t_rec, v_rec, t_sim, v_sim;
      double last_error = NAN;
      for (const Sample& s : sim) {
        const auto rec = track.At(w.t_change - lead + s.t, 0.04);
        if (!rec) continue;
        const double e = std::hypot(s.x - rec->x, s.y - rec->y);
        errors.push_back(e);
        heading_errors.push_back(AngleDifference(s.yaw, rec->yaw));
        last_error = e;
      }
      if (std::isfinite(last_error)) {
        end_errors.push_back(last_error);
        if (last_error > worst_error) {
          worst_error = last_error;
          char at[64];
          std::snprintf(at, sizeof at, " at %.1f s", w.t_change);
          worst = w.what + at;
        }
      }
      if (replayed < 2) {
        // The speed in the robot's frame along the commanded axis: recorded dots, simulated line.
        const bool turn = w.what.rfind("turn", 0) == 0;
        const bool left = w.what.rfind("left", 0) == 0;
        const auto component = [&](double yaw, double vx, double vy, double omega) {
          if (turn) return omega;
          const double c = std::cos(yaw), s = std::sin(yaw);
          return left ? -s * vx + c * vy : c * vx + s * vy;
        };
        for (const TrackPoint& p : track.points()) {
          if (p.t < w.t_change - lead || p.t > w.t_end) continue;
          const auto m = track.At(p.t, 0.05);
          if (!m) continue;
          t_rec.push_back(p.t - w.t_change);
          v_rec.push_back(component(m->yaw, m->vx, m->vy, m->omega));
        }
        for (const Sample& s : sim) {
          t_sim.push_back(s.t - lead);
          v_sim.push_back(component(s.yaw, s.vx, s.vy, s.omega));
        }
        validation::Plot p;
        char file[96];
        std::snprintf(file, sizeof file, "check-robot-%s-%d-%d.svg", r.robot.team == TeamColour::kBlue ? "blue" : "yellow",
                      r.robot.id, replayed);
        p.file = file;
        p.title = RobotName(r.robot) + ": " + w.what + ", recorded and simulated";
        p.x_label = "time after the command, s";
        p.y_label = turn ? "turn rate, rad/s" : (left ? "speed to the left, m/s" : "speed forward, m/s");
        p.series.push_back(Line("recorded (smoothed)", t_rec, v_rec, true));
        p.series.push_back(Line("fitted world", t_sim, v_sim));
        plots.push_back(p);
        images << "![" << p.title << "](" << p.file << ")\n\n";
      }
      ++replayed;
    }
    std::sort(end_errors.begin(), end_errors.end());
    char buf[240];
    std::snprintf(buf, sizeof buf, "| %s | %d | %.1f mm | %.1f mm | %.3f rad | %s (%.0f mm) |\n",
                  RobotName(r.robot).c_str(), replayed, 1e3 * Rms(errors),
                  end_errors.empty() ? NAN : 1e3 * end_errors[end_errors.size() / 2], Rms(heading_errors),
                  worst.c_str(), 1e3 * worst_error);
    md << buf;
  }
  if (robots == 0) md << "| (none: no robot with recorded commands is in the fitted world) | | | | | |\n";
  md << "\n" << images.str();
}

void CheckBall(const CheckInput& in, ReplayWorld& rw, std::ostringstream& md, std::vector<validation::Plot>& plots) {
  md << "### Ball: each free run started as recorded\n\n"
        "The ball is put where the run begins with the recorded velocity and the spin the fit gives it then "
        "(rolling, or still sliding for the rest of the fitted slide), every robot off the field; its simulated path "
        "is compared with the recorded one over the run.\n\n| run | start | speed | duration | error RMS | at the end |\n|---|---|---|---|---|---|\n";
  const BallFit& fit = in.fits->ball;
  const SmoothedTrack track(in.tracks->ball);
  const double radius = rw.world().GroundTruth().ball.radius;
  kernel::World& world = rw.world();
  int replayed = 0;
  std::vector<double> all_errors;
  validation::Plot plot;
  plot.file = "check-ball-runs.svg";
  plot.title = "Ball runs: distance travelled, recorded and simulated";
  plot.x_label = "time from the run's start, s";
  plot.y_label = "distance, m";
  for (std::size_t i = 0; i < fit.runs.size() && replayed < in.max_ball_runs; ++i) {
    const BallRun& run = fit.runs[i];
    if (!run.used || run.airborne) continue;
    const double session_t0 = run.t_begin + 0.04;
    const auto start = track.At(session_t0, 0.04);
    if (!start) continue;
    // Its spin as the fit has it then: rolling once the slide is over; while sliding, the slip
    // speed v − ωr falls at μg·(1 + 1/k) (friction slows the ball by μg and spins it up by μg/k),
    // so the slip left is what the fitted slide's remaining time takes away.
    const double speed = std::hypot(start->vx, start->vy);
    const double sliding_left = std::max(0.0, run.slide_time - (session_t0 - run.t_ref));
    const double mu_g = fit.mu.ok() ? fit.mu.value * 9.81 : 0.0;
    const double slip = std::min(speed, mu_g * (1 + 1 / rw.BallInertia()) * sliding_left);
    const double spin = speed - slip;
    rw.Ball(start->x, start->y, start->vx, start->vy, spin, radius);
    std::vector<double> errors, t_rec, d_rec, t_sim, d_sim;
    double last = NAN;
    // Recorded points of the run (raw detections), distance from the start.
    for (std::size_t k = track.LowerBound(session_t0); k < track.points().size() && track.points()[k].t <= run.t_end; ++k) {
      const TrackPoint& p = track.points()[k];
      t_rec.push_back(p.t - session_t0);
      d_rec.push_back(std::hypot(p.x - start->x, p.y - start->y));
    }
    // The teleport applies at the start of the next step: time counts from there.
    const double world_start = world.clock().seconds();
    while (world.clock().seconds() - world_start < run.t_end - session_t0) {
      world.Step();
      const double t = world.clock().seconds() - world_start;
      const Vec3& p = world.GroundTruth().ball.pose.position;
      if (const auto rec = track.At(session_t0 + t, 0.05)) {
        last = std::hypot(p.x() - rec->x, p.y() - rec->y);
        errors.push_back(last);
      }
      t_sim.push_back(t);
      d_sim.push_back(std::hypot(p.x() - start->x, p.y() - start->y));
    }
    all_errors.insert(all_errors.end(), errors.begin(), errors.end());
    char buf[240];
    std::snprintf(buf, sizeof buf, "| %zu | %.2f, %.2f m | %.2f m/s | %.2f s | %.1f mm | %.1f mm |\n", i + 1, start->x,
                  start->y, std::hypot(start->vx, start->vy), run.t_end - session_t0, 1e3 * Rms(errors), 1e3 * last);
    md << buf;
    if (replayed < 4) {
      plot.series.push_back(Line("run " + std::to_string(i + 1) + " recorded", t_rec, d_rec, true));
      plot.series.push_back(Line("run " + std::to_string(i + 1) + " simulated", t_sim, d_sim));
    }
    ++replayed;
  }
  if (replayed == 0) {
    md << "| (none: no free flat run was used by the fit) | | | | | |\n\n";
    return;
  }
  char buf[160];
  std::snprintf(buf, sizeof buf, "\nOver %d runs the simulated ball is %.1f mm (RMS) from the recorded one.\n\n", replayed,
                1e3 * Rms(all_errors));
  md << buf << "![" << plot.title << "](" << plot.file << ")\n\n";
  plots.push_back(plot);
}

}  // namespace

ReportSection RunCheck(const CheckInput& in) {
  ReportSection section;
  std::ostringstream md;
  ReplayWorld rw(in);
  if (in.fits->ball.enough_data) CheckBall(in, rw, md, section.plots);
  CheckRobots(in, rw, md, section.plots);
  section.markdown = md.str();
  return section;
}

}  // namespace ubersim::calibrate
