// SPDX-License-Identifier: Apache-2.0
// The shipped Div B world (real ODE, no sockets) with a match session beside it, stepped as a
// synchronous run steps it; "teams" shoot by giving the ball a new velocity where a kick leaves it.
#pragma once

#include <functional>
#include <memory>

#include "match_session.hpp"
#include "shipped_worlds.hpp"
#include "ubersim/kernel/world.hpp"

namespace ubersim::match {

struct RefereedWorld {
  /// Div B with a session of `options` (made network-free here).
  explicit RefereedWorld(MatchOptions options) {
    model = shipped.Load("div-b");
    world = std::make_unique<kernel::World>(model, shipped.registry, shipped.log, false);
    options.network = false;
    session = std::make_unique<MatchSession>(*world, std::move(options), shipped.log);
  }
  /// The referee's state now (the built-in one's, or the game controller's it follows).
  const Referee& state() const { return session->referee()->message(); }
  /// Steps until `done` (at most `limit` simulated seconds); false if it never held.
  bool StepUntil(const std::function<bool()>& done, double limit) {
    const std::int64_t end = world->clock().time_ns() + static_cast<std::int64_t>(limit * 1e9);
    while (world->clock().time_ns() < end) {
      if (done()) return true;
      world->Step();
      session->AfterStep();
    }
    return done();
  }
  /// Steps until the command is `c`.
  bool StepUntilCommand(Referee::Command c, double limit) {
    return StepUntil([&] { return state().command() == c; }, limit);
  }
  /// A kick as the ball leaves the robot: the ball at `from` with `velocity`.
  void Shoot(Vec3 from, Vec3 velocity) {
    PositionEvent e;
    e.target = Target::Ball();
    e.position = from;
    e.velocity = velocity;
    e.angular_velocity = Vec3::Zero();
    world->events().Post(e);
  }

  testing::ShippedWorlds shipped;
  kernel::WorldModel model;
  std::unique_ptr<kernel::World> world;
  std::unique_ptr<MatchSession> session;
};

}  // namespace ubersim::match
