// SPDX-License-Identifier: Apache-2.0
#include "vector_worlds.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace ubersim::python {

namespace {

double LimitOf(const std::optional<kernel::ComponentModel>& part, const char* block, const char* key,
               double fallback) {
  if (!part) return fallback;
  const ParamView& p = part->params;
  if (block == nullptr) return p.GetDouble(key, fallback);
  return p.Has(block) ? p[block].GetDouble(key, fallback) : fallback;
}

// The team's robots attack the goal at x = +length/2 (blue) or −length/2 (yellow), as the
// world files place them (blue in the half x < 0).
double AttackSign(Team team) { return team == Team::kBlue ? 1.0 : -1.0; }

}  // namespace

Team TeamNamed(const std::string& name) {
  if (name == "blue") return Team::kBlue;
  if (name == "yellow") return Team::kYellow;
  throw std::invalid_argument("team must be 'blue' or 'yellow', not '" + name + "'");
}

TeamDriver DriverNamed(const std::string& name) {
  if (name == "agent") return TeamDriver::kAgent;
  if (name == "idle") return TeamDriver::kIdle;
  if (name == "scripted") return TeamDriver::kScripted;
  if (name == "random") return TeamDriver::kRandom;
  throw std::invalid_argument("a team is driven by 'agent', 'idle', 'scripted' or 'random', not '" + name + "'");
}

VectorWorlds::VectorWorlds(apps::LoadedWorld loaded, const VectorWorldsOptions& options)
    : loaded_(std::move(loaded)), log_(log_text_, LogLevel::kError), options_(options) {
  if (options_.count < 1) throw std::invalid_argument("the number of worlds must be at least 1");
  if (options_.frame_skip < 1) throw std::invalid_argument("frame_skip must be at least 1");
  loaded_.model.transports.clear();  // no sockets: the caller drives the worlds
  for (int k = 0; k < options_.count; ++k) {
    auto instance = std::make_unique<Instance>();
    instance->world = std::make_unique<World>(loaded_.model, *loaded_.loading.registry, log_, false);
    worlds_.push_back(std::move(instance));
  }
  for (const RobotState& r : worlds_.front()->world->GroundTruth().robots) slots_.push_back(r.id);
  for (int i = 0; i < robots(); ++i) {
    const Team team = slots_[static_cast<std::size_t>(i)].team;
    if (options_.drivers[static_cast<int>(team)] == TeamDriver::kAgent) controlled_.push_back(i);
  }
  for (auto& w : worlds_) {
    Instance* at = w.get();
    at->robots_seen.assign(slots_.size(), {});
    at->present.assign(slots_.size(), false);
    at->robots_last.assign(slots_.size(), {});
    if (options_.camera_features) {
      at->world->SetVisionObserver([this, at](const VisionFrame& frame) {
        for (const DetectedRobot& d : frame.robots) {
          const auto slot = std::find(slots_.begin(), slots_.end(), d.id);
          if (slot == slots_.end()) continue;
          const auto i = static_cast<std::size_t>(slot - slots_.begin());
          at->robots_seen[i] = at->robots_last[i] = Seen{true, d.x, d.y, d.yaw};
        }
        if (!frame.balls.empty()) {
          const auto best = std::max_element(frame.balls.begin(), frame.balls.end(),
                                             [](const DetectedBall& a, const DetectedBall& b) {
                                               return a.confidence < b.confidence;
                                             });
          at->ball_seen = at->ball_last = Seen{true, best->x, best->y, 0.0};
        }
      });
    }
    StartDrivers(*w, loaded_.model.seed);
    RefreshPresence(*w);  // what the first actions are sent by
  }
}

void VectorWorlds::RefreshPresence(int index) { RefreshPresence(*worlds_.at(static_cast<std::size_t>(index))); }

void VectorWorlds::RefreshPresence(Instance& w) {
  const WorldSnapshot s = w.world->GroundTruth();
  for (std::size_t i = 0; i < slots_.size(); ++i) {
    w.present[i] = false;
    for (const RobotState& r : s.robots) {
      if (r.id == slots_[i]) w.present[i] = r.present;
    }
  }
}

VectorWorlds::~VectorWorlds() = default;

double VectorWorlds::step_seconds() const { return loaded_.model.physics.step; }

std::array<std::array<double, action::kCount>, 2> VectorWorlds::ActionBounds(int slot) const {
  const RobotId id = slots_.at(static_cast<std::size_t>(slot));
  const kernel::RobotModel* m = nullptr;
  for (const kernel::RobotPlacement& p : loaded_.model.robots) {
    if (p.id == id) m = p.model.get();
  }
  if (!m) m = loaded_.model.team_models[static_cast<int>(id.team)].get();
  const double speed = m ? LimitOf(m->drive, "limits", "max_speed", 3.0) : 3.0;
  const double turn = m ? LimitOf(m->drive, "limits", "max_angular_speed", 10.0) : 10.0;
  const double kick = m && m->kicker ? LimitOf(m->kicker, nullptr, "max_flat_speed", 6.5) : 0.0;
  const double chip = m && m->kicker ? M_PI / 4 : 0.0;
  const double roller = m && m->dribbler ? LimitOf(m->dribbler, nullptr, "max_speed", 150.0) : 0.0;
  return {{{-speed, -speed, -turn, 0.0, 0.0, 0.0}, {speed, speed, turn, kick, chip, roller}}};
}

void VectorWorlds::StartDrivers(Instance& w, std::uint64_t seed) {
  w.random_play.reset();
  w.scripted.clear();
  const bool blue_random = options_.drivers[0] == TeamDriver::kRandom;
  const bool yellow_random = options_.drivers[1] == TeamDriver::kRandom;
  if (blue_random || yellow_random) {
    // One random play for the teams it drives: the bench's own when it drives both.
    std::optional<Team> only;
    if (!(blue_random && yellow_random)) only = blue_random ? Team::kBlue : Team::kYellow;
    w.random_play = std::make_unique<apps::RandomPlay>(*w.world, seed, only);
  }
  for (Team team : {Team::kBlue, Team::kYellow}) {
    if (options_.drivers[static_cast<int>(team)] == TeamDriver::kScripted) w.scripted.emplace_back(team, AttackSign(team));
  }
}

void VectorWorlds::Reset(int index, std::uint64_t seed, const EpisodeStart& start, float* obs) {
  Instance& w = *worlds_.at(static_cast<std::size_t>(index));
  w.world->Reset(seed);
  const std::size_t n = slots_.size();
  if (!start.robot_pose.empty()) {
    if (start.robot_pose.size() != 3 * n || start.present.size() != n) {
      throw std::invalid_argument("an episode start needs a pose and a presence for each of the " +
                                  std::to_string(n) + " robots");
    }
    for (std::size_t i = 0; i < n; ++i) {
      PositionEvent e;
      e.target = Target::Robot(slots_[i]);
      e.present = start.present[i] != 0;
      if (start.present[i]) {
        e.position = Vec3(start.robot_pose[3 * i], start.robot_pose[3 * i + 1], 0.0);
        e.yaw = start.robot_pose[3 * i + 2];
        e.velocity = Vec3::Zero();
        e.angular_velocity = Vec3::Zero();
      }
      w.world->events().Post(std::move(e));
    }
  }
  if (start.has_ball) {
    PositionEvent e;
    e.target = Target::Ball();
    e.position = Vec3(start.ball[0], start.ball[1], start.ball[2]);
    e.velocity = Vec3(start.ball[3], start.ball[4], start.ball[5]);
    e.angular_velocity = Vec3::Zero();
    w.world->events().Post(std::move(e));
  }
  w.world->ProcessEvents();
  std::fill(w.robots_seen.begin(), w.robots_seen.end(), Seen{});
  std::fill(w.robots_last.begin(), w.robots_last.end(), Seen{});
  w.ball_seen = w.ball_last = Seen{};
  StartDrivers(w, seed);
  ObserveOne(w, obs);
}

void VectorWorlds::SendActions(Instance& w, const float* actions) {
  for (std::size_t c = 0; c < controlled_.size(); ++c) {
    const auto slot = static_cast<std::size_t>(controlled_[c]);
    // A robot that is off the field gets nothing: the world would refuse it and log each one.
    // (Teleports happen only in Reset, which observes: the last observation's presence holds.)
    if (!w.present[slot]) continue;
    const float* a = actions + c * action::kCount;
    CommandEvent e;
    e.robot = slots_[slot];
    e.move = LocalVelocityCommand{a[action::kForward], a[action::kLeft], a[action::kAngular]};
    if (a[action::kKickSpeed] > 0.0f) e.kick = KickCommand{a[action::kKickSpeed], a[action::kChipAngle]};
    e.dribbler_speed = std::max(0.0f, a[action::kDribbler]);
    w.world->events().Post(std::move(e));
  }
}

void VectorWorlds::Step(const float* actions, float* obs) {
  const std::size_t action_stride = controlled_.size() * action::kCount;
  const std::size_t obs_stride = slots_.size() * static_cast<std::size_t>(features());
  for (std::size_t k = 0; k < worlds_.size(); ++k) {
    Instance& w = *worlds_[k];
    SendActions(w, actions + k * action_stride);
    if (!w.scripted.empty()) {
      const WorldSnapshot now = w.world->GroundTruth();
      for (const ScriptedTeam& team : w.scripted) team.Command(*w.world, now);
    }
    for (int s = 0; s < options_.frame_skip; ++s) {
      if (w.random_play) w.random_play->BeforeStep();
      w.world->Step();
    }
    physics_steps_ += options_.frame_skip;
    ObserveOne(w, obs + k * obs_stride);
  }
}

void VectorWorlds::Observe(float* obs) {
  const std::size_t obs_stride = slots_.size() * static_cast<std::size_t>(features());
  for (std::size_t k = 0; k < worlds_.size(); ++k) ObserveOne(*worlds_[k], obs + k * obs_stride);
}

void VectorWorlds::ObserveOne(Instance& w, float* obs) {
  namespace f = feature;
  const WorldSnapshot s = w.world->GroundTruth();
  const int width = features();
  const Vec3 ball = s.ball.pose.position, ball_v = s.ball.twist.linear;
  for (std::size_t i = 0; i < slots_.size(); ++i) {
    float* row = obs + i * static_cast<std::size_t>(width);
    std::fill(row, row + width, 0.0f);
    const RobotState* r = i < s.robots.size() && s.robots[i].id == slots_[i] ? &s.robots[i] : nullptr;
    if (!r) {
      for (const RobotState& other : s.robots) {
        if (other.id == slots_[i]) r = &other;
      }
    }
    w.present[i] = r && r->present;
    if (w.present[i]) {
      const double yaw = r->pose.Yaw();
      row[f::kPresent] = 1.0f;
      row[f::kX] = static_cast<float>(r->pose.position.x());
      row[f::kY] = static_cast<float>(r->pose.position.y());
      row[f::kCosYaw] = static_cast<float>(std::cos(yaw));
      row[f::kSinYaw] = static_cast<float>(std::sin(yaw));
      row[f::kVx] = static_cast<float>(r->twist.linear.x());
      row[f::kVy] = static_cast<float>(r->twist.linear.y());
      row[f::kOmega] = static_cast<float>(r->twist.angular.z());
      row[f::kKickerReady] = r->kicker_ready ? 1.0f : 0.0f;
      row[f::kBallContact] = r->dribbler_ball_contact ? 1.0f : 0.0f;
    }
    row[f::kBallX] = static_cast<float>(ball.x());
    row[f::kBallY] = static_cast<float>(ball.y());
    row[f::kBallZ] = static_cast<float>(ball.z());
    row[f::kBallVx] = static_cast<float>(ball_v.x());
    row[f::kBallVy] = static_cast<float>(ball_v.y());
    row[f::kBallVz] = static_cast<float>(ball_v.z());
    if (options_.camera_features) {
      const Seen& seen = w.robots_last[i];
      row[f::kSeen] = w.robots_seen[i].seen ? 1.0f : 0.0f;
      row[f::kSeenX] = static_cast<float>(seen.x);
      row[f::kSeenY] = static_cast<float>(seen.y);
      row[f::kSeenCos] = seen.seen ? static_cast<float>(std::cos(seen.yaw)) : 0.0f;
      row[f::kSeenSin] = seen.seen ? static_cast<float>(std::sin(seen.yaw)) : 0.0f;
      row[f::kBallSeen] = w.ball_seen.seen ? 1.0f : 0.0f;
      row[f::kBallSeenX] = static_cast<float>(w.ball_last.x);
      row[f::kBallSeenY] = static_cast<float>(w.ball_last.y);
    }
  }
  if (options_.camera_features) {
    std::fill(w.robots_seen.begin(), w.robots_seen.end(), Seen{});
    w.ball_seen = Seen{};
  }
}

}  // namespace ubersim::python
