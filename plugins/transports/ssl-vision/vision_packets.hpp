// SPDX-License-Identifier: Apache-2.0
// SSL-Vision packets from ÜberSim's SI data: the only place the vision transport converts units.
#pragma once

#include <map>
#include <utility>
#include <vector>

#include <ubersim/world_state.hpp>

#include "ssl_vision_wrapper.pb.h"
#include "transport_common/wire_clock.hpp"

namespace ubersim::ssl_vision {

/// The ball models announced in the geometry (SSL_GeometryModels), m/s² and factors.
struct BallModels {
  double acc_slide = -3.43;             ///< sliding deceleration, m/s²
  double acc_roll = -0.36;              ///< rolling deceleration, m/s²
  double k_switch = 0.68;               ///< slide→roll at this fraction of the initial speed
  double damping_xy_first_hop = 0.66;   ///< horizontal factor, first bounce
  double damping_xy_other_hops = 0.95;  ///< horizontal factor, later bounces
  double damping_z = 0.55;              ///< vertical factor per bounce
};

/// The (dummy) intrinsics sent for every camera, pixels.
struct CameraIntrinsics {
  double focal_length = 390;      ///< px
  double principal_point_x = 300; ///< px
  double principal_point_y = 300; ///< px
  double distortion = 0.2;        ///< radial k1
  int image_width = 600;          ///< px
  int image_height = 600;         ///< px
};

/// Everything one geometry packet says, SI.
struct GeometryInputs {
  FieldGeometry field;              ///< sizes and markings, m
  std::vector<CameraInfo> cameras;  ///< ids and positions, m
  CameraIntrinsics intrinsics;      ///< sent for each camera
  BallModels models;                ///< ball models
  double ball_radius = 0.0215;      ///< m
  double max_robot_radius = 0.09;   ///< m
};

/// Robot heights by (team, id), m: what the detections report as `height`.
using RobotHeights = std::map<std::pair<int, int>, double>;

/// Where an ideal camera at `camera` looking straight down images the field point (x, y), px.
std::pair<double, double> PixelOf(const CameraIntrinsics& intrinsics, const Vec3& camera, double x, double y);

/// One detection packet for one camera frame (also when it saw nothing); `camera` may be null
/// (unknown camera: pixels at the principal point).
SSL_WrapperPacket DetectionPacket(const VisionFrame& frame, transport::WireClock& clock,
                                  const CameraIntrinsics& intrinsics, const CameraInfo* camera,
                                  const RobotHeights& heights);

/// One geometry packet: field, every camera's calibration, ball models.
SSL_WrapperPacket GeometryPacket(const GeometryInputs& in);

}  // namespace ubersim::ssl_vision
