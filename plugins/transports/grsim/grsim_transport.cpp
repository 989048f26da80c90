// SPDX-License-Identifier: Apache-2.0
// grsim: the legacy grSim protocol (docs/interfaces.md), so teams that speak only grSim work
// unchanged. grSim_Packet datagrams arrive on a UDP port (its own thread); their commands and
// replacements become command and position events. After each datagram with commands, the robots
// whose infrared or kick state changed are reported to the sender's IP as Robots_Status.
// Anything malformed is rejected with a counted, rate-limited warning, and the simulation runs on.
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <ubersim/ubersim.hpp>

#include "grsim_translator.hpp"
#include "transport_common/network.hpp"
#include "transport_common/reject_log.hpp"
#include "transport_common/udp_server.hpp"
#include "ubersim_plugin_schema.hpp"

namespace {

using ubersim::grsim::StatusTracker;
using ubersim::grsim::Translator;
using ubersim::grsim::WorldView;
using ubersim::transport::RejectLog;
using ubersim::transport::UdpEndpoint;
using ubersim::transport::UdpServer;

class GrsimTransport final : public ubersim::Transport {
 public:
  ~GrsimTransport() override { Stop(); }

  void Start(ubersim::TransportContext& ctx) override {
    const ubersim::ParamView& p = ctx.Params();
    events_ = &ctx.Events();
    status_port_blue_ = static_cast<std::uint16_t>(p.GetInt("status_port_blue", 30011));
    status_port_yellow_ = static_cast<std::uint16_t>(p.GetInt("status_port_yellow", 30012));
    translator_ = std::make_unique<Translator>(p.GetDouble("spinner_speed", 104.71975511965977));
    const ubersim::FieldGeometry& field = ctx.Field();
    world_.half_length = 0.5 * field.carpet_length;
    world_.half_width = 0.5 * field.carpet_width;
    rejects_ = std::make_unique<RejectLog>(ctx.Logger(), "grSim datagram rejected");

    UdpServer::Options o;
    o.addresses = ubersim::transport::ResolveAddresses(ubersim::transport::AddressSetting(p, "address", "auto"),
                                                       ctx.LocalOnly());
    o.port = static_cast<std::uint16_t>(p.GetInt("port", 20011));
    o.max_datagram = static_cast<std::size_t>(p.GetInt("max_datagram", 16384));
    o.name = "grsim";
    server_ = std::make_unique<UdpServer>(
        o, [this](std::span<const std::uint8_t> bytes, const UdpEndpoint& from) { OnDatagram(bytes, from); },
        [this](const std::string& why, const UdpEndpoint& from) {
          rejects_->Reject(why + " (from " + ubersim::transport::ToString(from) + ")");
        });
    server_->Start();
  }

  void Publish(const ubersim::WorldSnapshot& s) override {
    std::lock_guard lock(mutex_);
    if (world_.known && s.sim_time_ns < last_sim_ns_) translator_->ForgetSpinners();  // world reset
    last_sim_ns_ = s.sim_time_ns;
    if (!world_.known || world_.robots.size() != s.robots.size()) {
      world_.robots.clear();
      for (const ubersim::RobotState& r : s.robots) world_.robots.push_back(r.id);
      world_.known = true;
    }
    if (s.field) {  // the field may change while the world runs (the simulation protocol's geometry)
      world_.half_length = 0.5 * s.field->carpet_length;
      world_.half_width = 0.5 * s.field->carpet_width;
    }
    world_.ball_position = s.ball.pose.position;
    world_.ball_velocity = s.ball.twist.linear;
    world_.ball_radius = s.ball.radius;
    status_.Observe(s.robots, *translator_);
  }

  std::string Endpoint() const override {
    if (!server_) return {};
    std::string where;
    for (const UdpEndpoint& e : server_->LocalEndpoints()) {
      where += (where.empty() ? "" : ", ") + ubersim::transport::ToString(e);
    }
    return "udp " + where +
           " (robot status to the sender's IP at " + std::to_string(status_port_blue_) + " blue, " +
           std::to_string(status_port_yellow_) + " yellow)";
  }

  void Stop() override {
    if (server_) server_->Stop();
    if (rejects_) rejects_->Flush();
  }

 private:
  // Receive thread.
  void OnDatagram(std::span<const std::uint8_t> bytes, const UdpEndpoint& from) {
    const std::string sender = ubersim::transport::ToString(from);
    grSim_Packet packet;
    // Parsing fails on truncated or corrupt bytes and on missing required fields (proto2).
    if (!packet.ParseFromArray(bytes.data(), static_cast<int>(bytes.size()))) {
      rejects_->Reject("not a complete grSim_Packet, " + std::to_string(bytes.size()) + " bytes from " + sender);
      return;
    }
    std::vector<ubersim::Event> events;
    std::vector<std::string> reasons;
    {
      std::lock_guard lock(mutex_);
      translator_->Translate(packet, world_, events, reasons);
    }
    for (const std::string& why : reasons) rejects_->Reject(why + " (from " + sender + ")");
    for (ubersim::Event& e : events) events_->Post(std::move(e));
    if (packet.has_commands()) SendStatus(from);
  }

  void SendStatus(const UdpEndpoint& to) {
    std::pair<Robots_Status, Robots_Status> changed;
    {
      std::lock_guard lock(mutex_);
      changed = status_.TakeChanged();
    }
    std::string bytes;
    if (changed.first.robots_status_size() > 0 && changed.first.SerializeToString(&bytes)) {
      server_->Reply(UdpEndpoint(to.address(), status_port_blue_), AsBytes(bytes));
    }
    if (changed.second.robots_status_size() > 0 && changed.second.SerializeToString(&bytes)) {
      server_->Reply(UdpEndpoint(to.address(), status_port_yellow_), AsBytes(bytes));
    }
  }

  static std::span<const std::uint8_t> AsBytes(const std::string& s) {
    return {reinterpret_cast<const std::uint8_t*>(s.data()), s.size()};
  }

  ubersim::EventSink* events_ = nullptr;  // Post is thread-safe
  std::uint16_t status_port_blue_ = 30011;
  std::uint16_t status_port_yellow_ = 30012;
  std::unique_ptr<RejectLog> rejects_;  // thread-safe
  std::unique_ptr<UdpServer> server_;
  // Shared by the simulation thread (Publish) and the receive thread.
  std::mutex mutex_;
  WorldView world_;
  std::unique_ptr<Translator> translator_;
  StatusTracker status_;
  std::int64_t last_sim_ns_ = 0;
};

}  // namespace

UBERSIM_REGISTER_TRANSPORT(GrsimTransport, "grsim", "1.0.0", ubersim_plugin::kSchema)
