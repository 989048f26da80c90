// SPDX-License-Identifier: Apache-2.0
// The vision and radio presets and the default camera layout (read by the model loader).
#include "ubersim/kernel/perception.hpp"

namespace ubersim::kernel {

bool PerceptionPreset(const std::string& name, PerceptionModel& m) {
  m = PerceptionModel{};
  m.preset = name;
  if (name == "ideal") {
    return true;  // 60 Hz, no latency, no noise, nothing lost
  }
  if (name == "2003") {
    // The ÜberSim paper: 30 Hz vision with about 100 ms from capture to the team's software.
    // Noise and drop-outs of that era's cameras are not given; plausible values, a little worse
    // than today's 3 mm (physics.md §4).
    m.frame_rate = 30;
    m.latency = 0.1;
    m.ball_position_sigma = 0.005;
    m.robot_position_sigma = 0.005;
    m.robot_orientation_sigma = 0.035;  // 2°
    m.ball_drop = 0.05;
    m.robot_drop = 0.02;
    return true;
  }
  if (name == "realistic") {
    // Today's league (physics.md §4): 75 Hz cameras (the Basler acA1300-75gc ssl-vision is run
    // with); noise, drop-outs and overlap of the ER-Force simulator's "Realistic" preset, which
    // was tuned against real ssl-vision; 35 ms from capture to packet (its vision delay).
    m.frame_rate = 75;
    m.latency = 0.035;
    m.ball_position_sigma = 0.0014;
    m.robot_position_sigma = 0.0013;
    m.robot_orientation_sigma = 0.01;
    m.ball_drop = 0.05;
    m.robot_drop = 0.02;
    m.camera_overlap = 1.0;
    return true;
  }
  return false;
}

bool RadioPreset(const std::string& name, RadioModel& m) {
  m = RadioModel{};
  m.preset = name;
  if (name == "ideal") return true;
  if (name == "2003") {
    // Not in the paper; the radios of the time (physics.md §4: ≈200 ms for a whole DECT-era
    // loop) were slow and lossy: plausible values.
    m.latency = 0.02;
    m.loss = 0.05;
    return true;
  }
  if (name == "realistic") {
    // ER-Force simulator's "Realistic" preset (physics.md §4): 3 ms command delay, 3 % loss.
    m.latency = 0.003;
    m.loss = 0.03;
    return true;
  }
  return false;
}

std::vector<CameraModel> CameraGrid(int count, double length, double width, double height) {
  const int rows = count >= 4 && count % 2 == 0 ? 2 : 1;
  const int columns = count / rows;
  std::vector<CameraModel> cameras;
  for (int row = 0; row < rows; ++row) {
    for (int col = 0; col < columns; ++col) {
      CameraModel c;
      c.id = static_cast<int>(cameras.size());
      c.x_min = -0.5 * length + length * col / columns;
      c.x_max = -0.5 * length + length * (col + 1) / columns;
      c.y_min = 0.5 * width - width * (row + 1) / rows;
      c.y_max = 0.5 * width - width * row / rows;
      c.position = Vec3(0.5 * (c.x_min + c.x_max), 0.5 * (c.y_min + c.y_max), height);
      cameras.push_back(c);
    }
  }
  return cameras;
}

}  // namespace ubersim::kernel
