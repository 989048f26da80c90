// SPDX-License-Identifier: Apache-2.0
#include "ubersim/kernel/runner.hpp"

#include <algorithm>
#include <chrono>
#include <thread>

namespace ubersim::kernel {

RunStatus RunWorld(World& world, const RunOptions& options, const std::atomic<bool>& stop,
                   const std::function<void(const RunStatus&)>& on_status) {
  using Clock = std::chrono::steady_clock;
  ClockControl& control = world.clock_control();
  control.speed_factor = std::max(0.0, options.speed_factor);
  control.paused = options.start_paused;
  const auto duration_ns = static_cast<std::int64_t>(options.duration * 1e9 + 0.5);
  const std::int64_t start_ns = world.clock().time_ns();

  Pacer pacer;
  RunStatus status;
  auto last_report = Clock::now();
  double last_sim = world.clock().seconds();
  const auto report_every = std::chrono::duration<double>(options.status_interval);
  auto report = [&](bool finished) {
    const auto now = Clock::now();
    const double wall = std::chrono::duration<double>(now - last_report).count();
    status.sim_time = world.clock().seconds();
    status.steps = world.clock().steps();
    status.real_time_factor = wall > 0 ? (status.sim_time - last_sim) / wall : 0.0;
    status.paused = control.paused;
    status.finished = finished;
    last_report = now;
    last_sim = status.sim_time;
    if (on_status) on_status(status);
  };

  // Events posted before the loop (a transport pausing the world as it starts) apply before
  // the first step.
  world.ProcessEvents();
  while (!stop.load(std::memory_order_relaxed) && !world.stopped()) {
    if (options.between_steps) options.between_steps();
    if (duration_ns > 0 && world.clock().time_ns() - start_ns >= duration_ns) break;
    if (Clock::now() - last_report >= report_every) report(false);
    if (control.paused && control.pending_steps == 0) {
      world.ProcessEvents();
      pacer.Reanchor();
      // The events just processed may have asked for steps (a synchronous client): run them at
      // once rather than after the wait.
      if (control.pending_steps == 0) world.events().WaitForEvent(std::chrono::milliseconds(20));
      continue;
    }
    const bool single_step = control.paused && control.pending_steps > 0;
    if (single_step) {
      // Steps asked for one by one (a viewer's step button, a synchronous client) run at once.
      world.Step();
      --control.pending_steps;
      continue;
    }
    const auto wait =
        pacer.WaitBefore(world.clock().time_ns() + world.clock().step_ns(), control.speed_factor);
    if (wait > Clock::duration::zero()) {
      // Sleep in short slices so events (pause, stop) are seen promptly.
      std::this_thread::sleep_for(std::min<Clock::duration>(wait, std::chrono::milliseconds(5)));
      if (wait > std::chrono::milliseconds(5)) {
        world.ProcessEvents();
        continue;
      }
    }
    world.Step();
  }
  report(true);
  return status;
}

}  // namespace ubersim::kernel
