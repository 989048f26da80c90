// SPDX-License-Identifier: Apache-2.0
#include "vision_packets.hpp"

#include <algorithm>

#include "transport_common/wire_units.hpp"

namespace ubersim::ssl_vision {
namespace {

using transport::MetresToMm;
using transport::MetresToWholeMm;

int TeamKey(Team t) { return t == Team::kBlue ? 0 : 1; }

void SetPoint(Vector2f* v, double x, double y) {
  v->set_x(static_cast<float>(MetresToMm(x)));
  v->set_y(static_cast<float>(MetresToMm(y)));
}

}  // namespace

std::pair<double, double> PixelOf(const CameraIntrinsics& in, const Vec3& camera, double x, double y) {
  const double height = std::max(camera.z(), 1e-3);  // a camera on the carpet would divide by 0
  // Image x along the field's +x, image y down (towards the field's −y), as seen from above.
  return {in.principal_point_x + in.focal_length * (x - camera.x()) / height,
          in.principal_point_y - in.focal_length * (y - camera.y()) / height};
}

SSL_WrapperPacket DetectionPacket(const VisionFrame& frame, transport::WireClock& clock,
                                  const CameraIntrinsics& intrinsics, const CameraInfo* camera,
                                  const RobotHeights& heights) {
  SSL_WrapperPacket packet;
  SSL_DetectionFrame* d = packet.mutable_detection();
  d->set_frame_number(frame.frame_number);
  d->set_t_capture(clock.Seconds(frame.t_capture_ns));
  d->set_t_sent(clock.Seconds(frame.t_sent_ns));
  d->set_t_capture_camera(transport::NsToSeconds(frame.t_capture_ns));  // the camera's clock: sim time
  d->set_camera_id(static_cast<std::uint32_t>(frame.camera_id));
  const auto pixel = [&](double x, double y) {
    return camera ? PixelOf(intrinsics, camera->position, x, y)
                  : std::pair{intrinsics.principal_point_x, intrinsics.principal_point_y};
  };
  for (const DetectedBall& b : frame.balls) {
    SSL_DetectionBall* out = d->add_balls();
    out->set_confidence(static_cast<float>(b.confidence));
    out->set_area(transport::WholePixels(b.area));  // the blob in the image, whole pixels
    out->set_x(static_cast<float>(MetresToMm(b.x)));
    out->set_y(static_cast<float>(MetresToMm(b.y)));
    const auto [px, py] = pixel(b.x, b.y);
    out->set_pixel_x(static_cast<float>(px));
    out->set_pixel_y(static_cast<float>(py));
  }
  for (const DetectedRobot& r : frame.robots) {
    SSL_DetectionRobot* out = r.id.team == Team::kBlue ? d->add_robots_blue() : d->add_robots_yellow();
    out->set_confidence(static_cast<float>(r.confidence));
    out->set_robot_id(static_cast<std::uint32_t>(r.id.id));
    out->set_x(static_cast<float>(MetresToMm(r.x)));
    out->set_y(static_cast<float>(MetresToMm(r.y)));
    out->set_orientation(static_cast<float>(r.yaw));
    const auto [px, py] = pixel(r.x, r.y);
    out->set_pixel_x(static_cast<float>(px));
    out->set_pixel_y(static_cast<float>(py));
    const auto h = heights.find({TeamKey(r.id.team), r.id.id});
    if (h != heights.end()) out->set_height(static_cast<float>(MetresToMm(h->second)));
  }
  return packet;
}

SSL_WrapperPacket GeometryPacket(const GeometryInputs& in) {
  SSL_WrapperPacket packet;
  SSL_GeometryData* g = packet.mutable_geometry();
  SSL_GeometryFieldSize* f = g->mutable_field();
  const FieldGeometry& field = in.field;
  f->set_field_length(MetresToWholeMm(field.field_length));
  f->set_field_width(MetresToWholeMm(field.field_width));
  f->set_goal_width(MetresToWholeMm(field.goal_width));
  f->set_goal_depth(MetresToWholeMm(field.goal_depth));
  f->set_boundary_width(MetresToWholeMm(field.boundary_width));
  for (const FieldLine& l : field.lines) {
    SSL_FieldLineSegment* out = f->add_field_lines();
    out->set_name(l.name);
    SetPoint(out->mutable_p1(), l.x1, l.y1);
    SetPoint(out->mutable_p2(), l.x2, l.y2);
    out->set_thickness(static_cast<float>(MetresToMm(l.thickness)));
    SSL_FieldShapeType type;
    if (SSL_FieldShapeType_Parse(l.name, &type)) out->set_type(type);  // ÜberSim names lines by type
  }
  for (const FieldArc& a : field.arcs) {
    SSL_FieldCircularArc* out = f->add_field_arcs();
    out->set_name(a.name);
    SetPoint(out->mutable_center(), a.cx, a.cy);
    out->set_radius(static_cast<float>(MetresToMm(a.radius)));
    out->set_a1(static_cast<float>(a.a1));
    out->set_a2(static_cast<float>(a.a2));
    out->set_thickness(static_cast<float>(MetresToMm(a.thickness)));
    SSL_FieldShapeType type;
    if (SSL_FieldShapeType_Parse(a.name, &type)) out->set_type(type);
  }
  f->set_penalty_area_depth(MetresToWholeMm(field.penalty_area_depth));
  f->set_penalty_area_width(MetresToWholeMm(field.penalty_area_width));
  f->set_center_circle_radius(MetresToWholeMm(field.center_circle_radius));
  f->set_line_thickness(MetresToWholeMm(field.line_thickness));
  f->set_goal_center_to_penalty_mark(MetresToWholeMm(field.goal_center_to_penalty_mark));
  f->set_goal_height(MetresToWholeMm(field.goal_height));
  f->set_ball_radius(static_cast<float>(MetresToMm(in.ball_radius)));
  f->set_max_robot_radius(static_cast<float>(MetresToMm(in.max_robot_radius)));
  if (field.carpet_length > field.field_length) {
    f->set_boundary_width_goal_line(MetresToWholeMm(0.5 * (field.carpet_length - field.field_length)));
  }

  for (const CameraInfo& c : in.cameras) {
    SSL_GeometryCameraCalibration* out = g->add_calib();
    const CameraIntrinsics& k = in.intrinsics;
    out->set_camera_id(static_cast<std::uint32_t>(c.id));
    out->set_focal_length(static_cast<float>(k.focal_length));
    out->set_principal_point_x(static_cast<float>(k.principal_point_x));
    out->set_principal_point_y(static_cast<float>(k.principal_point_y));
    out->set_distortion(static_cast<float>(k.distortion));
    // Dummy extrinsics, the values the league's simulators send; teams use derived_camera_world_*.
    out->set_q0(0.7f);
    out->set_q1(0.7f);
    out->set_q2(0.7f);
    out->set_q3(0.7f);
    out->set_tx(0.0f);
    out->set_ty(0.0f);
    out->set_tz(3500.0f);
    out->set_derived_camera_world_tx(static_cast<float>(MetresToMm(c.position.x())));
    out->set_derived_camera_world_ty(static_cast<float>(MetresToMm(c.position.y())));
    out->set_derived_camera_world_tz(static_cast<float>(MetresToMm(c.position.z())));
    out->set_pixel_image_width(static_cast<std::uint32_t>(k.image_width));
    out->set_pixel_image_height(static_cast<std::uint32_t>(k.image_height));
  }

  SSL_GeometryModels* models = g->mutable_models();
  SSL_BallModelStraightTwoPhase* straight = models->mutable_straight_two_phase();
  straight->set_acc_slide(in.models.acc_slide);
  straight->set_acc_roll(in.models.acc_roll);
  straight->set_k_switch(in.models.k_switch);
  SSL_BallModelChipFixedLoss* chip = models->mutable_chip_fixed_loss();
  chip->set_damping_xy_first_hop(in.models.damping_xy_first_hop);
  chip->set_damping_xy_other_hops(in.models.damping_xy_other_hops);
  chip->set_damping_z(in.models.damping_z);
  return packet;
}

}  // namespace ubersim::ssl_vision
