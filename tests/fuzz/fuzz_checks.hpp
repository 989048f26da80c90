// SPDX-License-Identifier: Apache-2.0
// What every fuzz target checks beyond "no crash": a decoder that accepted an input hands the
// kernel only finite numbers. A broken promise aborts, which libFuzzer reports as a crash and
// the replay test as a failure.
#pragma once

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <type_traits>
#include <variant>
#include <vector>

#include <ubersim/events.hpp>

namespace ubersim::fuzz {

/// Aborts with `what` unless `ok`.
inline void Check(bool ok, const char* what) {
  if (ok) return;
  std::fprintf(stderr, "fuzz check failed: %s\n", what);
  std::abort();
}

inline bool Finite(double v) { return std::isfinite(v); }
inline bool Finite(const Vec3& v) { return v.allFinite(); }
template <typename T>
bool Finite(const std::optional<T>& v) {
  return !v || Finite(*v);
}

/// Every number in `events` is finite.
inline void CheckFinite(const std::vector<Event>& events) {
  for (const Event& e : events) {
    std::visit(
        [](const auto& ev) {
          using T = std::decay_t<decltype(ev)>;
          if constexpr (std::is_same_v<T, PositionEvent>) {
            Check(Finite(ev.position) && Finite(ev.yaw) && Finite(ev.velocity) && Finite(ev.angular_velocity),
                  "position event with a non-finite value");
          } else if constexpr (std::is_same_v<T, CommandEvent>) {
            bool ok = Finite(ev.dribbler_speed) && (!ev.kick || (Finite(ev.kick->speed) && Finite(ev.kick->angle)));
            if (ev.move) {
              std::visit(
                  [&ok](const auto& m) {
                    using M = std::decay_t<decltype(m)>;
                    if constexpr (std::is_same_v<M, WheelSpeedCommand>) {
                      for (double w : m.wheel_speeds) ok = ok && Finite(w);
                    } else if constexpr (std::is_same_v<M, LocalVelocityCommand>) {
                      ok = ok && Finite(m.forward) && Finite(m.left) && Finite(m.angular);
                    } else {
                      ok = ok && Finite(m.x) && Finite(m.y) && Finite(m.angular);
                    }
                  },
                  *ev.move);
            }
            Check(ok, "command event with a non-finite value");
          } else if constexpr (std::is_same_v<T, ClockEvent>) {
            Check(Finite(ev.speed_factor) && ev.speed_factor >= 0 && ev.steps >= 1, "clock event out of range");
          } else if constexpr (std::is_same_v<T, RealismEvent>) {
            Check(Finite(ev.vision_latency) && Finite(ev.ball_position_noise) && Finite(ev.robot_position_noise) &&
                      Finite(ev.robot_orientation_noise) && Finite(ev.ball_drop) && Finite(ev.robot_drop) &&
                      Finite(ev.camera_overlap) && Finite(ev.radio_latency) && Finite(ev.radio_loss),
                  "realism event with a non-finite value");
          } else if constexpr (std::is_same_v<T, RobotSpecEvent>) {
            const RobotSpec& s = ev.spec;
            bool ok = Finite(s.radius) && Finite(s.height) && Finite(s.mass) && Finite(s.center_to_dribbler) &&
                      Finite(s.max_flat_kick_speed) && Finite(s.max_chip_kick_speed) && Finite(s.max_speed) &&
                      Finite(s.max_angular_speed) && Finite(s.max_acceleration) && Finite(s.max_angular_acceleration) &&
                      Finite(s.max_deceleration) && Finite(s.max_angular_deceleration) && Finite(s.dribbler_width);
            if (s.wheel_angles) {
              for (double a : *s.wheel_angles) ok = ok && Finite(a);
            }
            Check(ok && ev.robot.id >= 0 && ev.robot.id <= 15, "robot spec event with a non-finite value or bad id");
          } else if constexpr (std::is_same_v<T, FieldEvent>) {
            Check(Finite(ev.field_length) && Finite(ev.field_width), "field event with a non-finite size");
          }
        },
        e);
  }
}

}  // namespace ubersim::fuzz
