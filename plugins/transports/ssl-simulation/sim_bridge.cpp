// SPDX-License-Identifier: Apache-2.0
#include "sim_bridge.hpp"

#include <algorithm>

namespace ubersim::ssl_simulation {

void SimBridge::OnVisionFrame(const VisionFrame& frame) {
  std::lock_guard lock(mutex_);
  if (armed_ && !complete_) frames_.push_back(frame);
}

void SimBridge::OnPublish(const WorldSnapshot& snapshot) {
  std::lock_guard lock(mutex_);
  robots_.resize(snapshot.robots.size());
  for (std::size_t i = 0; i < snapshot.robots.size(); ++i) {
    const RobotState& from = snapshot.robots[i];
    RobotEntry& to = robots_[i];
    to.id = from.id;
    to.present = from.present;
    to.report.dribbler_ball_contact = from.dribbler_ball_contact;
    to.report.feedback_lost = from.feedback_lost;
    // Assigned into the kept entry, so the wheel speeds' storage is reused step after step.
    if (!from.drive) {
      to.report.drive.reset();
    } else if (to.report.drive) {
      to.report.drive->wheel_speeds.assign(from.drive->wheel_speeds.begin(), from.drive->wheel_speeds.end());
      to.report.drive->local_velocity = from.drive->local_velocity;
    } else {
      to.report.drive = from.drive;
    }
  }
  has_state_ = true;
  ball_radius_ = snapshot.ball.radius;
  // The kernel's step is fixed and integral in ns, so time / steps is exact.
  if (snapshot.step > 0) step_ns_ = snapshot.sim_time_ns / snapshot.step;
  if (armed_ && !complete_ && --remaining_ <= 0) {
    complete_ = true;
    result_step_ = snapshot.step;
    result_time_ns_ = snapshot.sim_time_ns;
    done_.notify_all();
  }
}

bool SimBridge::HasState() const {
  std::lock_guard lock(mutex_);
  return has_state_;
}

const SimBridge::RobotEntry* SimBridge::Find(const RobotId& id) const {
  for (const RobotEntry& r : robots_) {
    if (r.id == id) return &r;
  }
  return nullptr;
}

bool SimBridge::Exists(const RobotId& id) const {
  std::lock_guard lock(mutex_);
  return Find(id) != nullptr;
}

bool SimBridge::OnField(const RobotId& id) const {
  std::lock_guard lock(mutex_);
  const RobotEntry* r = Find(id);
  return r && r->present;
}

std::optional<RobotReport> SimBridge::Report(const RobotId& id) const {
  std::lock_guard lock(mutex_);
  const RobotEntry* r = Find(id);
  if (!r || !r->present) return std::nullopt;
  return r->report;
}

double SimBridge::BallRadius() const {
  std::lock_guard lock(mutex_);
  return ball_radius_;
}

std::int64_t SimBridge::StepNs() const {
  std::lock_guard lock(mutex_);
  return step_ns_;
}

void SimBridge::Arm(std::int64_t steps) {
  std::lock_guard lock(mutex_);
  armed_ = true;
  complete_ = false;
  remaining_ = std::max<std::int64_t>(1, steps);
  frames_.clear();
}

std::optional<StepResult> SimBridge::Wait(std::chrono::steady_clock::duration timeout) {
  std::unique_lock lock(mutex_);
  const bool ok = done_.wait_for(lock, timeout, [this] { return complete_ || cancelled_; }) && complete_;
  armed_ = false;
  if (!ok) {
    frames_.clear();
    return std::nullopt;
  }
  StepResult r;
  r.frames.swap(frames_);
  r.step = result_step_;
  r.sim_time_ns = result_time_ns_;
  return r;
}

void SimBridge::Cancel() {
  std::lock_guard lock(mutex_);
  cancelled_ = true;
  done_.notify_all();
}

}  // namespace ubersim::ssl_simulation
