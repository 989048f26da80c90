// SPDX-License-Identifier: Apache-2.0
#include "session_tracks.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ubersim::calibrate {
namespace {

// A chain of ball detections, one per frame at most.
struct Chain {
  std::vector<TrackPoint> points;
  double vx = 0, vy = 0;  // m/s, from its last two points a few frames apart
  bool Predict(double t, double& x, double& y) const {
    const TrackPoint& p = points.back();
    x = p.x + vx * (t - p.t);
    y = p.y + vy * (t - p.t);
    return true;
  }
  void Add(const TrackPoint& p) {
    points.push_back(p);
    // Velocity over about 30 ms, so the noise of one detection does not swing the prediction.
    for (auto it = points.rbegin() + 1; it != points.rend(); ++it) {
      if (p.t - it->t >= 0.03) {
        vx = (p.x - it->x) / (p.t - it->t);
        vy = (p.y - it->y) / (p.t - it->t);
        return;
      }
    }
  }
};

std::vector<TrackPoint> Merge(std::vector<Chain>& chains, int min_points, std::int64_t& false_balls) {
  std::vector<TrackPoint> out;
  for (auto& c : chains) {
    if (static_cast<int>(c.points.size()) < min_points) {
      false_balls += static_cast<std::int64_t>(c.points.size());
      continue;
    }
    out.insert(out.end(), c.points.begin(), c.points.end());
  }
  std::stable_sort(out.begin(), out.end(), [](const TrackPoint& a, const TrackPoint& b) { return a.t < b.t; });
  return out;
}

// Position of a time-ordered track at t, linearly interpolated; false when t is not within 0.2 s
// of a point on both sides (or of one point).
bool Interpolate(const std::vector<TrackPoint>& track, double t, double& x, double& y) {
  const auto it = std::lower_bound(track.begin(), track.end(), t, [](const TrackPoint& p, double v) { return p.t < v; });
  constexpr double kReach = 0.2;
  if (it == track.end()) {
    if (track.empty() || t - track.back().t > kReach) return false;
    x = track.back().x;
    y = track.back().y;
    return true;
  }
  if (it == track.begin()) {
    if (it->t - t > kReach) return false;
    x = it->x;
    y = it->y;
    return true;
  }
  const TrackPoint& b = *it;
  const TrackPoint& a = *(it - 1);
  if (b.t - a.t > 2 * kReach) {
    const TrackPoint& near = (t - a.t < b.t - t) ? a : b;
    if (std::abs(near.t - t) > kReach) return false;
    x = near.x;
    y = near.y;
    return true;
  }
  const double w = b.t > a.t ? (t - a.t) / (b.t - a.t) : 0.0;
  x = a.x + w * (b.x - a.x);
  y = a.y + w * (b.y - a.y);
  return true;
}

}  // namespace

SessionTracks BuildTracks(const LogSession& session, const BallTrackingOptions& options) {
  SessionTracks tracks;
  std::vector<Chain> open, closed;
  for (const CameraFrame& f : session.frames) {
    for (const RobotDetection& r : f.robots) {
      tracks.robots[r.robot].push_back({f.t_capture, r.x, r.y, r.yaw, f.camera_id});
    }
    // Chains unseen too long are finished.
    for (auto it = open.begin(); it != open.end();) {
      if (f.t_capture - it->points.back().t > options.max_gap) {
        closed.push_back(std::move(*it));
        it = open.erase(it);
      } else {
        ++it;
      }
    }
    // Each detection joins the nearest chain that predicts it within the gate (a chain takes at
    // most one detection of a frame); the rest start chains of their own.
    std::vector<bool> taken(open.size(), false);
    for (const BallDetection& b : f.balls) {
      int best = -1;
      double best_d = std::numeric_limits<double>::infinity();
      for (std::size_t i = 0; i < open.size(); ++i) {
        if (taken[i]) continue;
        double px = 0, py = 0;
        open[i].Predict(f.t_capture, px, py);
        const double d = std::hypot(b.x - px, b.y - py);
        const double gate = options.gate + options.max_ball_speed * (f.t_capture - open[i].points.back().t);
        if (d <= gate && d < best_d) {
          best = static_cast<int>(i);
          best_d = d;
        }
      }
      const TrackPoint p{f.t_capture, b.x, b.y, 0.0, f.camera_id};
      if (best >= 0) {
        open[best].Add(p);
        taken[best] = true;
      } else {
        open.emplace_back();
        open.back().Add(p);
        taken.push_back(true);
      }
    }
  }
  for (auto& c : open) closed.push_back(std::move(c));
  tracks.ball = Merge(closed, options.min_points, tracks.false_balls);
  return tracks;
}

double SessionTracks::NearestRobot(double t, double x, double y) const {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& [key, track] : robots) {
    double rx = 0, ry = 0;
    if (Interpolate(track, t, rx, ry)) best = std::min(best, std::hypot(rx - x, ry - y));
  }
  return best;
}

std::vector<CommandSample> LocalCommands(const LogSession& session, const SessionTracks& tracks, const RobotKey& robot) {
  std::vector<CommandSample> out;
  const auto c = session.commands.find(robot);
  if (c == session.commands.end()) return out;
  const auto& global = session.command_is_global.at(robot);
  const auto t = tracks.robots.find(robot);
  for (std::size_t i = 0; i < c->second.size(); ++i) {
    CommandSample s = c->second[i];
    if (global[i]) {
      if (t == tracks.robots.end()) continue;
      const auto& track = t->second;
      const auto it = std::lower_bound(track.begin(), track.end(), s.t,
                                       [](const TrackPoint& p, double v) { return p.t < v; });
      const TrackPoint* near = it != track.end() ? &*it : (track.empty() ? nullptr : &track.back());
      if (!near || std::abs(near->t - s.t) > 0.1 || !std::isfinite(near->yaw)) continue;
      const double cy = std::cos(near->yaw), sy = std::sin(near->yaw);
      const double fx = s.forward, fy = s.left;
      s.forward = cy * fx + sy * fy;
      s.left = -sy * fx + cy * fy;
    }
    out.push_back(s);
  }
  return out;
}

}  // namespace ubersim::calibrate
