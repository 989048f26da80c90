// SPDX-License-Identifier: Apache-2.0
// ssl_simulation: the league's simulation protocol. SimulatorCommand on the control port,
// RobotControl on one port per team, each datagram answered to its sender; optionally a TCP
// server for synchronous stepping. Network threads only parse, map (mapping.hpp) and post events;
// they learn the world from SimBridge, which the simulation thread fills in Publish.
#include <chrono>
#include <cmath>
#include <functional>
#include <future>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include <boost/asio/io_context.hpp>
#include <ubersim/ubersim.hpp>

#include "error_codes.hpp"
#include "mapping.hpp"
#include "sim_bridge.hpp"
#include "sync_server.hpp"
#include "transport_common/network.hpp"
#include "transport_common/reject_log.hpp"
#include "transport_common/udp_server.hpp"
#include "ubersim_plugin_schema.hpp"

// Inside the project's namespace: the wire messages' global Team and RobotId must not win lookup.
namespace ubersim::ssl_simulation {
namespace {

using namespace std::chrono_literals;

// How long a reply waits for the world's answer to a change it asked for (a robot coming on, specs).
constexpr auto kAnswerTimeout = 2s;
using transport::DropReason;
using transport::RejectLog;
using transport::UdpEndpoint;
using transport::UdpServer;

// A request port: turns a datagram into its reply, or a refusal (an error found before the
// content was read, e.g. UBERSIM_OVERSIZED) into that port's response type.
struct UdpPort {
  std::string name;  // "control", "blue", "yellow"
  std::function<std::string(std::string_view datagram)> answer;
  std::function<std::string(const WireError& error)> refuse;
  std::unique_ptr<UdpServer> server;
};

std::span<const std::uint8_t> AsBytes(const std::string& s) {
  return {reinterpret_cast<const std::uint8_t*>(s.data()), s.size()};
}

struct SyncSettings {
  std::uint16_t port = 0;
  Team team = Team::kBlue;
  double max_step = 1.0;        // s
  std::size_t max_clients = 4;
  double timeout = 10.0;        // s of wall time
};

class SslSimulationTransport final : public Transport {
 public:
  ~SslSimulationTransport() override { Stop(); }

  void Start(TransportContext& context) override {
    context_ = &context;
    const ParamView& p = context.Params();
    addresses_ = transport::ResolveAddresses(transport::AddressSetting(p, "address", "auto"), context.LocalOnly());
    max_message_ = static_cast<std::size_t>(p.GetInt("max_message_size", 16384));
    if (p.Has("wheel_velocity_order")) {
      options_.wheel_order.clear();
      const ParamView order = p["wheel_velocity_order"];
      for (std::size_t i = 0; i < order.Size(); ++i) options_.wheel_order.push_back(static_cast<int>(order.At(i).AsInt()));
      if (!options_.wheel_order.empty() && options_.wheel_order.size() != 4) {
        throw order.Error("needs 4 wheel indices (front_right, back_right, back_left, front_left) or none");
      }
    }
    refused_ = std::make_unique<RejectLog>(context.Logger(), "message refused", 1s, "refused");
    dropped_ = std::make_unique<RejectLog>(context.Logger(), "udp datagram dropped", 1s);

    try {
      OpenUdp(p.GetInt("control_port", 10300), "control", [this](std::string_view d) { return OnControl(d); },
              [](const WireError& e) { return Refusal<SimulatorResponse>(e); });
      OpenUdp(p.GetInt("blue_port", 10301), "blue",
              [this](std::string_view d) { return OnRobotControl(Team::kBlue, d); },
              [](const WireError& e) { return Refusal<RobotControlResponse>(e); });
      OpenUdp(p.GetInt("yellow_port", 10302), "yellow",
              [this](std::string_view d) { return OnRobotControl(Team::kYellow, d); },
              [](const WireError& e) { return Refusal<RobotControlResponse>(e); });
      if (p.Has("sync")) {
        const ParamView s = p["sync"];
        sync_.port = static_cast<std::uint16_t>(s["port"].AsInt());
        sync_.team = s.GetString("team", "blue") == "yellow" ? Team::kYellow : Team::kBlue;
        sync_.max_step = s.GetDouble("max_step", sync_.max_step);
        sync_.max_clients = static_cast<std::size_t>(s.GetInt("max_clients", 4));
        sync_.timeout = s.GetDouble("timeout", sync_.timeout);
        // Synchronous stepping is for tools on this machine or named ones: the first address only.
        sync_server_ = std::make_unique<SyncServer>(io_, addresses_.front(), sync_.port, max_message_, sync_.max_clients,
                                                    context.Logger(),
                                                    [this](const SimulationSyncRequest& r) { return OnSync(r); });
        // No real-time clock may drive a synchronous world: it steps only when a client asks.
        ClockEvent pause;
        pause.action = ClockEvent::Action::kPause;
        context.Events().Post(pause);
      }
    } catch (const std::runtime_error& e) {
      throw PluginError(e.what());
    }
    for (auto& port : udp_) port->server->Start();
    if (sync_server_) {
      sync_server_->Start();
      io_thread_ = std::thread([this] { io_.run(); });
    }
  }

  void Publish(const WorldSnapshot& snapshot) override { bridge_.OnPublish(snapshot); }
  void OnVisionFrame(const VisionFrame& frame) override { bridge_.OnVisionFrame(frame); }

  std::string Endpoint() const override {
    std::string out = "udp";
    for (std::size_t i = 0; i < udp_.size(); ++i) {
      out += (i ? ", " : " ") + std::to_string(udp_[i]->server->LocalEndpoint().port()) + " (" + udp_[i]->name + ")";
    }
    out += " on";
    for (std::size_t i = 0; i < addresses_.size(); ++i) out += (i ? ", " : " ") + transport::DescribeAddress(addresses_[i]);
    if (sync_server_) {
      out += "; tcp " + addresses_.front() + ":" + std::to_string(sync_.port) + " (sync, " + ToString(sync_.team) + ")";
    }
    return out;
  }

  void Stop() override {
    // The worker first (it may wait for steps that will not come), then the sockets' threads.
    bridge_.Cancel();
    for (auto& port : udp_) port->server->Stop();
    if (sync_server_) sync_server_->StopWorker();
    io_.stop();
    if (io_thread_.joinable()) io_thread_.join();
    sync_server_.reset();
    udp_.clear();
    if (refused_) refused_->Flush();
    if (dropped_) dropped_->Flush();
  }

 private:
  // Binds one request port; every datagram is answered to its sender, also one too large to read.
  void OpenUdp(std::int64_t port, const char* name, std::function<std::string(std::string_view)> answer,
               std::function<std::string(const WireError&)> refuse) {
    if (port == 0) return;  // switched off in the world file
    auto p = std::make_unique<UdpPort>(UdpPort{name, std::move(answer), std::move(refuse), nullptr});
    UdpPort* raw = p.get();  // stays put: the port is owned through a pointer
    UdpServer::Options o;
    o.addresses = addresses_;
    o.port = static_cast<std::uint16_t>(port);
    o.max_datagram = max_message_;
    o.name = std::string("ssl_simulation ") + name;
    raw->server = std::make_unique<UdpServer>(
        o,
        [raw](std::span<const std::uint8_t> bytes, const UdpEndpoint& from) {
          // Always answered, even with zero bytes (an empty response message). Best effort, as UDP
          // is: a full socket buffer or a vanished client loses this reply only.
          const std::string reply =
              raw->answer(std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
          raw->server->Reply(from, AsBytes(reply));
        },
        [this, raw](const DropReason& why, const UdpEndpoint& from) { OnDrop(*raw, why, from); });
    udp_.push_back(std::move(p));
  }

  void OnDrop(UdpPort& port, const DropReason& why, const UdpEndpoint& from) {
    if (why.kind != DropReason::Kind::kOversized) {
      dropped_->Reject(port.name + ": " + why.text + " (" + transport::ToString(from) + ")");
      return;
    }
    const WireError e{codes::kOversized, why.text + " (max_message_size)"};
    CountRefused(port.name.c_str(), {e});
    port.server->Reply(from, AsBytes(port.refuse(e)));
  }

  // The reply to a message refused before it was read: the port's response with that one error.
  template <typename Response>
  static std::string Refusal(const WireError& e) {
    Response r;
    AppendErrors({e}, r.mutable_errors());
    return r.SerializeAsString();
  }

  // Where a robot is. Before the first step there is no published state, so ask the kernel
  // (queries are answered even while paused); bounded, so a stalled world cannot hang us.
  Presence Where(const RobotId& id) {
    if (bridge_.HasState()) {
      if (!bridge_.Exists(id)) return Presence::kAbsent;
      return bridge_.OnField(id) ? Presence::kOnField : Presence::kOffField;
    }
    auto answer = std::make_shared<std::promise<Presence>>();
    std::future<Presence> found = answer->get_future();
    QueryEvent q;
    q.target = Target::Robot(id);
    q.reply = [answer](const ObjectState& s) {
      answer->set_value(!s.found ? Presence::kAbsent : s.present ? Presence::kOnField : Presence::kOffField);
    };
    context_->Events().Post(std::move(q));
    return found.wait_for(500ms) == std::future_status::ready ? found.get() : Presence::kAbsent;
  }

  std::optional<RobotReport> Report(const RobotId& id) {
    if (bridge_.HasState()) return bridge_.Report(id);
    return Where(id) == Presence::kOnField ? std::optional<RobotReport>(RobotReport{}) : std::nullopt;
  }

  MappingOptions Options() const {
    MappingOptions o = options_;
    o.ball_radius = bridge_.BallRadius();
    return o;
  }

  // Posts the events; for those whose answer belongs in the reply (robots coming on, specs, the
  // field, the vision port) waits for the world's answer and appends its errors. Bounded: a
  // world that does not answer in time is said so in the reply.
  void Post(std::vector<Event>& events, std::vector<WireError>& errors) {
    std::vector<std::pair<Event, std::future<EventAnswer>>> waiting;
    for (Event& e : events) {
      if (!WantsAnswer(e)) {
        context_->Events().Post(std::move(e));
        continue;
      }
      auto promise = std::make_shared<std::promise<EventAnswer>>();
      std::future<EventAnswer> answer = promise->get_future();
      std::visit(
          [&](auto& ev) {
            if constexpr (requires { ev.reply = EventReply(); }) {
              ev.reply = [promise](const EventAnswer& a) { promise->set_value(a); };
            }
          },
          e);
      Event copy = e;  // what the answer is about (its reply is never called twice: it is not posted)
      context_->Events().Post(std::move(e));
      waiting.emplace_back(std::move(copy), std::move(answer));
    }
    const auto deadline = std::chrono::steady_clock::now() + kAnswerTimeout;
    for (auto& [event, answer] : waiting) {
      if (answer.wait_until(deadline) != std::future_status::ready) {
        errors.push_back({codes::kRobotNotBuilt, "the world did not answer within 2 s (is it stopped?); the change may "
                                                 "still apply"});
        continue;
      }
      for (WireError& w : AnswerErrors(event, answer.get())) errors.push_back(std::move(w));
    }
  }

  void CountRefused(const char* port, const std::vector<WireError>& errors) {
    if (errors.empty()) return;
    refused_->Reject(std::string(port) + ": " + errors.front().code + ": " + errors.front().message);
  }

  std::string OnControl(std::string_view datagram) {
    SimulatorCommand command;
    if (auto e = ParseMessage(datagram.data(), datagram.size(), max_message_, command)) {
      CountRefused("control", {*e});
      return Refusal<SimulatorResponse>(*e);
    }
    SimulatorResponse response;
    Mapped m = MapSimulatorCommand(command, [this](const RobotId& id) { return Where(id); }, Options());
    Post(m.events, m.errors);
    CountRefused("control", m.errors);
    AppendErrors(m.errors, response.mutable_errors());
    // Every datagram gets an answer, even an empty one, so a client knows it arrived.
    return response.SerializeAsString();
  }

  std::string OnRobotControl(Team team, std::string_view datagram) {
    RobotControl control;
    const char* port = team == Team::kBlue ? "blue" : "yellow";
    if (auto e = ParseMessage(datagram.data(), datagram.size(), max_message_, control)) {
      CountRefused(port, {*e});
      return Refusal<RobotControlResponse>(*e);
    }
    MappedRobotControl m = MapRobotControl(control, team, [this](const RobotId& id) { return Where(id); }, Options());
    CountRefused(port, m.errors);
    Post(m.events, m.errors);
    return BuildRobotControlResponse(m.commanded_ids, team, [this](const RobotId& id) { return Report(id); },
                                     m.errors)
        .SerializeAsString();
  }

  // Runs on the sync worker: apply the request, step, wait for the simulation thread.
  SimulationSyncResponse OnSync(const SimulationSyncRequest& request) {
    SimulationSyncResponse response;
    std::vector<WireError> errors;
    std::vector<std::uint32_t> ids;
    const double sim_step = request.has_sim_step() ? request.sim_step() : 0.0;
    if (!std::isfinite(sim_step) || sim_step < 0 || sim_step > sync_.max_step) {
      errors.push_back({codes::kSyncStep, "sim_step must be in [0, " + std::to_string(sync_.max_step) + "] s"});
      CountRefused("sync", errors);
      AppendErrors(errors, response.mutable_robot_control_response()->mutable_errors());
      return response;
    }
    auto where = [this](const RobotId& id) { return Where(id); };
    if (request.has_simulator_command()) {
      Mapped m = MapSimulatorCommand(request.simulator_command(), where, Options());
      Post(m.events, m.errors);
      errors.insert(errors.end(), m.errors.begin(), m.errors.end());
    }
    if (request.has_robot_control()) {
      MappedRobotControl m = MapRobotControl(request.robot_control(), sync_.team, where, Options());
      Post(m.events, m.errors);
      ids = m.commanded_ids;
      errors.insert(errors.end(), m.errors.begin(), m.errors.end());
    }
    if (sim_step > 0) {
      const auto timeout = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
          std::chrono::duration<double>(std::max(sync_.timeout, 20.0 * sim_step)));
      std::vector<VisionFrame> frames;
      bool ok = true;
      std::int64_t step_ns = bridge_.StepNs();
      std::int64_t done = 0;
      if (step_ns == 0) {
        // Nothing published yet, so the step length is unknown: one step tells it.
        ok = RunSteps(1, timeout, frames);
        done = 1;
        step_ns = bridge_.StepNs();
      }
      if (ok && step_ns > 0) {
        // Whole physics steps, rounded to nearest; any positive sim_step is at least one.
        const auto total = std::max<std::int64_t>(1, std::llround(sim_step * 1e9 / static_cast<double>(step_ns)));
        if (total > done) ok = RunSteps(total - done, timeout, frames);
      }
      if (!ok) {
        errors.push_back({codes::kSyncTimeout, "the world did not finish the steps within the timeout"});
      }
      for (const VisionFrame& f : frames) *response.add_detection() = ToDetectionFrame(f);
    }
    *response.mutable_robot_control_response() =
        BuildRobotControlResponse(ids, sync_.team, [this](const RobotId& id) { return Report(id); }, errors);
    return response;
  }

  bool RunSteps(std::int64_t steps, std::chrono::steady_clock::duration timeout, std::vector<VisionFrame>& frames) {
    // Armed before the step event is posted: the paused world publishes nothing in between.
    bridge_.Arm(steps);
    ClockEvent step;
    step.action = ClockEvent::Action::kStep;
    step.steps = static_cast<int>(steps);
    context_->Events().Post(step);
    std::optional<StepResult> r = bridge_.Wait(timeout);
    if (!r) return false;
    frames.insert(frames.end(), r->frames.begin(), r->frames.end());
    return true;
  }

  TransportContext* context_ = nullptr;
  std::vector<std::string> addresses_;  // the request ports' (every one on each)
  std::size_t max_message_ = 16384;
  MappingOptions options_;
  SyncSettings sync_;
  SimBridge bridge_;
  std::unique_ptr<RejectLog> refused_;  // messages refused with an error reply; thread-safe
  std::unique_ptr<RejectLog> dropped_;  // datagrams lost to the network (failed receives and replies)
  std::vector<std::unique_ptr<UdpPort>> udp_;  // each with its own receive thread
  // The io_context (sync's TCP sockets) outlives every socket made on it (reverse destruction order).
  boost::asio::io_context io_;
  std::unique_ptr<SyncServer> sync_server_;
  std::thread io_thread_;
};

}  // namespace
}  // namespace ubersim::ssl_simulation

UBERSIM_REGISTER_TRANSPORT(ubersim::ssl_simulation::SslSimulationTransport, "ssl_simulation", "1.0.0", ubersim_plugin::kSchema)
