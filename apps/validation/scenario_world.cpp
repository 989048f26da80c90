// SPDX-License-Identifier: Apache-2.0
#include "scenario_world.hpp"

#include <stdexcept>

namespace ubersim::validation::detail {
namespace {

kernel::ModelLoader Loader(const Environment& env) {
  kernel::PluginRegistry* registry = env.registry;
  return kernel::ModelLoader(env.schema_dir, [registry](PluginKind kind, const std::string& id) {
    return registry->Find(kind, id).schema_json;
  });
}

}  // namespace

kernel::WorldModel LoadWorld(const Environment& env, const std::string& world) {
  kernel::WorldModel w = Loader(env).LoadWorld(env.models_dir / world);
  w.radio = kernel::RadioModel{};  // the physics is measured here, not the radio: no delay, no loss
  env.physics.ApplyTo(w.physics);
  return w;
}

std::shared_ptr<const kernel::RobotModel> LoadRobot(const Environment& env, const std::string& robot) {
  return Loader(env).LoadRobot(env.models_dir / robot);
}

kernel::WorldModel OneRobotWorld(const Environment& env, const std::string& world, const std::string& robot_file,
                                 double x, double y, double yaw) {
  kernel::WorldModel w = LoadWorld(env, world);
  w.robots.clear();
  w.robots.push_back(kernel::RobotPlacement{kRobot, LoadRobot(env, robot_file), x, y, yaw, true});
  return w;
}

Bench::Bench(const Environment& env, const kernel::WorldModel& model)
    : world_(std::make_unique<kernel::World>(model, *env.registry, *env.log, /*start_transports=*/false)) {}

void Bench::Drive(const RobotId& robot, const MoveCommand& command, double seconds, double radio_period) {
  const double dt = world_->clock().step_seconds();
  const long steps = std::lround(seconds / dt);
  const long every = std::max(1L, std::lround(radio_period / dt));
  for (long i = 0; i < steps; ++i) {
    if (i % every == 0) world_->events().Post(CommandEvent{robot, command, {}, {}});
    world_->Step();
  }
}

RobotState Bench::Robot(const RobotId& id) const {
  for (const RobotState& r : world_->GroundTruth().robots) {
    if (r.id == id) return r;
  }
  throw std::out_of_range("no robot " + ToString(id));
}

void Bench::Apply(Event e) {
  world_->events().Post(std::move(e));
  world_->ProcessEvents();
}

Line FitLine(const std::vector<double>& x, const std::vector<double>& y) {
  const std::size_t n = std::min(x.size(), y.size());
  if (n < 2) return {};
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < n; ++i) {
    sx += x[i]; sy += y[i]; sxx += x[i] * x[i]; sxy += x[i] * y[i];
  }
  const double nn = static_cast<double>(n);
  const double den = nn * sxx - sx * sx;
  if (std::abs(den) < 1e-300) return {};
  const double slope = (nn * sxy - sx * sy) / den;
  return {slope, (sy - slope * sx) / nn};
}

double SpeedUpSlope(const std::vector<double>& t, const std::vector<double>& v, double target, std::size_t count) {
  std::vector<double> tf, vf;
  const std::size_t n = count ? std::min(count, t.size()) : t.size();
  for (std::size_t i = 0; i < n; ++i) {
    if (v[i] > 0.2 * target && v[i] < 0.8 * target) {
      tf.push_back(t[i]);
      vf.push_back(v[i]);
    }
  }
  return FitLine(tf, vf).slope;
}

Metric Band(std::string name, double value, std::string unit, double low, double high, std::string basis) {
  return Metric{std::move(name), value, std::move(unit), low, high, std::move(basis)};
}

}  // namespace ubersim::validation::detail
