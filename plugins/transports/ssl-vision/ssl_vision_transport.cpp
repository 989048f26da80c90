// SPDX-License-Identifier: Apache-2.0
// ssl_vision: the simulated cameras as SSL-Vision packets on UDP multicast (docs/interfaces.md).
//
// Each camera frame that leaves the kernel's perception pipeline becomes one SSL_WrapperPacket
// with a detection frame, sent at once from the simulation thread (also when the camera saw
// nothing, as the real system does). The field geometry goes out in packets of its own at start
// and every geometry_interval of wall-clock time from a small thread, so a client that joins
// late, or while the world is paused, still learns the field.
#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include <ubersim/ubersim.hpp>

#include "transport_common/multicast_sender.hpp"
#include "transport_common/network.hpp"
#include "transport_common/reject_log.hpp"
#include "transport_common/wire_clock.hpp"
#include "ubersim_plugin_schema.hpp"
#include "vision_packets.hpp"

namespace {

using ubersim::ParamView;
using ubersim::ssl_vision::BallModels;
using ubersim::ssl_vision::CameraIntrinsics;
using ubersim::ssl_vision::GeometryInputs;
using ubersim::transport::MulticastSender;
using ubersim::transport::RejectLog;
using ubersim::transport::WireClock;

BallModels ReadBallModels(const ParamView& p) {
  BallModels m;
  if (!p.Has("ball_model")) return m;
  const ParamView b = p["ball_model"];
  if (b.Has("straight_two_phase")) {
    const ParamView s = b["straight_two_phase"];
    m.acc_slide = s.GetDouble("acc_slide", m.acc_slide);
    m.acc_roll = s.GetDouble("acc_roll", m.acc_roll);
    m.k_switch = s.GetDouble("k_switch", m.k_switch);
  }
  if (b.Has("chip_fixed_loss")) {
    const ParamView c = b["chip_fixed_loss"];
    m.damping_xy_first_hop = c.GetDouble("damping_xy_first_hop", m.damping_xy_first_hop);
    m.damping_xy_other_hops = c.GetDouble("damping_xy_other_hops", m.damping_xy_other_hops);
    m.damping_z = c.GetDouble("damping_z", m.damping_z);
  }
  return m;
}

CameraIntrinsics ReadIntrinsics(const ParamView& p) {
  CameraIntrinsics k;
  if (!p.Has("camera_calibration")) return k;
  const ParamView c = p["camera_calibration"];
  k.focal_length = c.GetDouble("focal_length", k.focal_length);
  k.principal_point_x = c.GetDouble("principal_point_x", k.principal_point_x);
  k.principal_point_y = c.GetDouble("principal_point_y", k.principal_point_y);
  k.distortion = c.GetDouble("distortion", k.distortion);
  k.image_width = static_cast<int>(c.GetInt("image_width", k.image_width));
  k.image_height = static_cast<int>(c.GetInt("image_height", k.image_height));
  return k;
}

bool SameCameras(const std::vector<ubersim::CameraInfo>& a, const std::vector<ubersim::CameraInfo>& b) {
  return std::equal(a.begin(), a.end(), b.begin(), b.end(), [](const auto& x, const auto& y) {
    return x.id == y.id && x.position == y.position;
  });
}

std::span<const std::uint8_t> Bytes(const std::string& s) {
  return {reinterpret_cast<const std::uint8_t*>(s.data()), s.size()};
}

class SslVisionTransport final : public ubersim::Transport {
 public:
  ~SslVisionTransport() override { Stop(); }

  void Start(ubersim::TransportContext& ctx) override {
    const ParamView& p = ctx.Params();
    MulticastSender::Options o;
    o.group = p.GetString("address", o.group);
    o.port = static_cast<std::uint16_t>(p.GetInt("port", o.port));
    o.interfaces = ubersim::transport::AddressSetting(p, "interface", "auto");
    o.local_only = ctx.LocalOnly();
    o.ttl = static_cast<int>(p.GetInt("ttl", o.ttl));
    o.name = "ssl_vision";
    interval_ = std::chrono::duration<double>(p.GetDouble("geometry_interval", 3.0));
    try {
      clock_ = std::make_unique<WireClock>(ubersim::transport::ParseTimestampMode(p.GetString("timestamps", "unix")));
    } catch (const std::invalid_argument& e) {
      throw p["timestamps"].Error(e.what());
    }
    context_ = &ctx;
    geometry_.field = ctx.Field();
    geometry_.cameras = ctx.Cameras();
    geometry_.intrinsics = ReadIntrinsics(p);
    geometry_.models = ReadBallModels(p);
    options_ = o;
    sender_ = std::make_unique<MulticastSender>(o);
    send_log_ = std::make_unique<RejectLog>(ctx.Logger(), "vision packet not sent");
    WarnIfUnreachable(ctx.Logger());

    RebuildGeometry();
    SendGeometry();
    stopping_ = false;
    geometry_thread_ = std::thread([this] { GeometryLoop(); });
  }

  void Publish(const ubersim::WorldSnapshot& s) override {
    clock_->Update(s.sim_time_ns);
    // Robots come and go and are rebuilt with other specs, and the field may change: the
    // heights detections carry and the geometry follow (the geometry is sent again at once).
    bool changed = false;
    double max_radius = 0.0;
    for (const ubersim::RobotState& r : s.robots) {
      double& height = heights_[{r.id.team == ubersim::Team::kBlue ? 0 : 1, r.id.id}];
      height = r.height;
      max_radius = std::max(max_radius, r.radius);
    }
    if (max_radius <= 0.0) max_radius = geometry_.max_robot_radius;  // no robots: keep it
    if (max_radius != geometry_.max_robot_radius || s.ball.radius != geometry_.ball_radius) {
      geometry_.max_robot_radius = max_radius;
      geometry_.ball_radius = s.ball.radius;
      changed = true;
    }
    if (s.field && (s.field->name != geometry_.field.name || s.field->field_length != geometry_.field.field_length ||
                    s.field->field_width != geometry_.field.field_width)) {
      geometry_.field = *s.field;
      changed = true;
    }
    // The cameras as reported: a new field brings its own, and the league's camera_position_error
    // (a realism setting, changeable at any time) moves the positions in the calibration.
    std::vector<ubersim::CameraInfo> cameras = context_->Cameras();
    if (!SameCameras(cameras, geometry_.cameras)) {
      geometry_.cameras = std::move(cameras);
      changed = true;
    }
    if (changed) {
      RebuildGeometry();
      SendGeometry();
    }
  }

  void OnVisionFrame(const ubersim::VisionFrame& frame) override {
    clock_->Update(frame.t_sent_ns);  // a frame leaves at its send time: that is now
    const ubersim::CameraInfo* camera = nullptr;
    for (const auto& c : geometry_.cameras) {
      if (c.id == frame.camera_id) camera = &c;
    }
    const SSL_WrapperPacket packet =
        ubersim::ssl_vision::DetectionPacket(frame, *clock_, geometry_.intrinsics, camera, heights_);
    packet.SerializeToString(&buffer_);
    Send(buffer_);
  }

  // The simulation protocol's vision_port: the same packets from now on to the new port.
  bool OnSetting(const std::string& name, std::int64_t value) override {
    if (name != "vision_port") return false;
    if (value < 1 || value > 65535) throw ubersim::PluginError("vision_port " + std::to_string(value) + " is not a port");
    MulticastSender::Options o = options_;
    o.port = static_cast<std::uint16_t>(value);
    std::unique_ptr<MulticastSender> next;
    try {
      next = std::make_unique<MulticastSender>(o);
    } catch (const std::runtime_error& e) {
      throw ubersim::PluginError(e.what());  // a refusal of the value, not a fault: the old port stays
    }
    {
      std::lock_guard lock(send_mutex_);
      std::swap(sender_, next);
    }
    options_ = o;
    SendGeometry();
    return true;
  }

  std::string Endpoint() const override { return sender_ ? sender_->Describe() : std::string(); }

  void Stop() override {
    {
      std::lock_guard lock(mutex_);
      stopping_ = true;
    }
    wake_.notify_all();
    if (geometry_thread_.joinable()) geometry_thread_.join();
    if (send_log_) send_log_->Flush();
  }

 private:
  // The league's Go tools (game controller, ssl-vision-client, log recorder, simulation
  // controller) listen only on interfaces with the MULTICAST flag, which Linux's loopback lacks
  // by default: said once, with the fix, when loopback is all vision goes out on.
  void WarnIfUnreachable(ubersim::Log& log) const {
    bool other = false, flagless_loopback = false;
    for (const std::string& a : sender_->Interfaces()) {
      const auto i = ubersim::transport::InterfaceWithAddress(a);
      if (!i) {
        other = other || !a.empty();
      } else if (i->loopback) {
        flagless_loopback = flagless_loopback || !i->multicast;
      } else {
        other = other || i->up;
      }
    }
    if (flagless_loopback && !other) {
      log.Warning("vision goes out on loopback only, and loopback has no MULTICAST flag: team software "
                  "that joins on 127.0.0.1 receives it, the league's Go tools (game controller, "
                  "ssl-vision-client, ssl-log-recorder) do not; to fix it run `sudo ip link set lo "
                  "multicast on` (docs/league-tools.md)");
    }
  }

  // Serialises the geometry for the thread to resend (simulation thread).
  void RebuildGeometry() {
    std::string bytes;
    ubersim::ssl_vision::GeometryPacket(geometry_).SerializeToString(&bytes);
    std::lock_guard lock(mutex_);
    geometry_bytes_ = std::move(bytes);
  }

  void SendGeometry() {
    std::string bytes;
    {
      std::lock_guard lock(mutex_);
      bytes = geometry_bytes_;
    }
    Send(bytes);
  }

  void Send(const std::string& bytes) {
    std::lock_guard lock(send_mutex_);
    if (!sender_->Send(Bytes(bytes))) send_log_->Reject(sender_->LastError());
  }

  void GeometryLoop() {
    std::unique_lock lock(mutex_);
    while (!wake_.wait_for(lock, interval_, [this] { return stopping_; })) {
      const std::string bytes = geometry_bytes_;
      lock.unlock();
      Send(bytes);
      lock.lock();
    }
  }

  // Simulation thread only.
  ubersim::TransportContext* context_ = nullptr;
  std::unique_ptr<WireClock> clock_;
  GeometryInputs geometry_;
  ubersim::ssl_vision::RobotHeights heights_;
  std::string buffer_;
  MulticastSender::Options options_;
  // Shared with the geometry thread.
  std::unique_ptr<MulticastSender> sender_;   // Send is thread-safe; replaced under mutex_
  std::unique_ptr<RejectLog> send_log_;       // thread-safe
  std::chrono::duration<double> interval_{3.0};
  std::mutex mutex_;
  std::mutex send_mutex_;  // sender_ is swapped (vision_port) while the geometry thread may send
  std::condition_variable wake_;
  bool stopping_ = false;
  std::string geometry_bytes_;
  std::thread geometry_thread_;
};

}  // namespace

UBERSIM_REGISTER_TRANSPORT(SslVisionTransport, "ssl_vision", "1.0.0", ubersim_plugin::kSchema)
