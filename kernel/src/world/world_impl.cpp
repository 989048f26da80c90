// SPDX-License-Identifier: Apache-2.0
#include "world/world_impl.hpp"

#include <chrono>
#include <cmath>
#include <algorithm>
#include <cstring>
#include <exception>
#include <optional>
#include <type_traits>

#include "ubersim/error.hpp"
#include "physics/field_builder.hpp"
#include "ubersim/kernel/logging.hpp"
#include "state/check_world.hpp"
#include "util/fnv1a.hpp"
#include "world/robot.hpp"

namespace ubersim::kernel {

namespace {

// A placed ball may overlap what it touches by this much, m (a contact's own surface layer and
// some: a ball put against a robot's face stays exactly where put).
constexpr double kPlacedBallOverlap = 0.001;
// How far from where it was put a placed ball is searched a free spot, m.
constexpr double kPlacedBallSearch = 0.3;

using SteadyClock = std::chrono::steady_clock;

std::int64_t ElapsedNs(SteadyClock::time_point since) {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(SteadyClock::now() - since).count();
}

bool Finite(const std::optional<Vec3>& v) { return !v || v->allFinite(); }



}  // namespace

/// A running transport with its context.
class TransportHost final : public TransportContext {
 public:
  TransportHost(const TransportModel& model, WorldImpl& world, Log& log, EventSink& events,
                const FieldGeometry& field, const std::string& world_name, FaultMonitor& faults)
      : world_(world),
        faults_(faults),
        plugin_(model.plugin),
        params_(model.params),
        log_(log, "transport " + model.plugin),
        events_(events),
        field_(field),
        world_name_(world_name) {}
  ~TransportHost() override { Stop(); }

  const ParamView& Params() const override { return params_; }
  Log& Logger() override { return log_; }
  EventSink& Events() override { return events_; }
  const FieldGeometry& Field() const override { return field_; }
  const std::string& WorldName() const override { return world_name_; }
  std::vector<CameraInfo> Cameras() const override {
    std::vector<CameraInfo> out;
    const PerceptionModel& vision = world_.perception();
    for (const CameraModel& c : vision.cameras) out.push_back(CameraInfo{c.id, ReportedCameraPosition(vision, c)});
    return out;
  }
  bool LocalOnly() const override { return world_.model().local_only; }

  void Start(std::shared_ptr<Transport> t, std::string file) {
    transport_ = std::move(t);
    file_ = std::move(file);
    try {
      transport_->Start(*this);
      started_ = true;
    } catch (const std::exception& e) {
      throw PluginError("transport plugin '" + plugin_ + "' failed to start: " + e.what());
    }
  }
  void Stop() {
    if (started_) {
      started_ = false;
      try {
        transport_->Stop();
      } catch (const std::exception& e) {
        log_.Error(std::string("Stop threw: ") + e.what());
      }
    }
    transport_.reset();
  }
  // Runs f against the transport; a throwing transport is a fault: reported once and switched
  // off (its threads keep running until the world stops it, but it is never called again).
  template <typename F>
  void Guarded(const char* phase, F&& f) {
    if (!started_ || failed_) return;
    std::string what;
    try {
      f(*transport_);
      return;
    } catch (const std::exception& e) {
      what = "threw " + ExceptionText(e);
    } catch (...) {
      what = "threw an exception that is not a std::exception";
    }
    failed_ = true;
    PluginFault fault;
    fault.kind = PluginKind::kTransport;
    fault.plugin = plugin_;
    fault.file = file_;
    fault.phase = phase;
    fault.what = what;
    faults_.Report(std::move(fault));
  }
  std::string Endpoint() const {
    return plugin_ + (transport_ ? ": " + transport_->Endpoint() : std::string());
  }
  // Offers a setting: true when taken; a PluginError is the transport refusing the value (its
  // message goes to `refusal`), anything else thrown is a fault.
  bool OnSetting(const std::string& name, std::int64_t value, std::string& refusal) {
    bool taken = false;
    Guarded("OnSetting", [&](Transport& t) {
      try {
        taken = t.OnSetting(name, value);
      } catch (const PluginError& e) {
        refusal = plugin_ + ": " + e.what();
      }
    });
    return taken;
  }

 private:
  const WorldImpl& world_;
  FaultMonitor& faults_;
  std::string plugin_;
  std::string file_;
  ParamView params_;
  PrefixedLog log_;
  EventSink& events_;
  const FieldGeometry& field_;
  const std::string& world_name_;
  std::shared_ptr<Transport> transport_;
  bool started_ = false;
  bool failed_ = false;
};

WorldImpl::WorldImpl(const WorldModel& model, PluginRegistry& registry, Log& log, bool start_transports)
    : model_(model),
      registry_(registry),
      log_(log),
      start_transports_(start_transports),
      clock_(model.physics.step),
      ode_random_seed_(static_cast<unsigned long>(model.seed)),
      perception_(model.perception, model.seed),
      radio_(model.radio, model.seed),
      held_ball_(model.held_ball),
      faults_(ParseFaultPolicy(model.on_plugin_fault), log) {
  if (!model_.field || !model_.ball) throw std::runtime_error("world has no field or ball model");
  field_geometry_ = model_.field->geometry;
  initial_field_ = model_.field;
  roster_ = model_.robots;
  Build();
  if (start_transports_) {
    for (const TransportModel& tm : model_.transports) {
      auto host = std::make_unique<TransportHost>(tm, *this, log_, events_, field_geometry_,
                                                  model_.name, faults_);
      std::shared_ptr<Transport> transport = registry_.CreateTransport(tm.plugin);
      host->Start(std::move(transport), registry_.Find(PluginKind::kTransport, tm.plugin).file.string());
      transports_.push_back(std::move(host));
    }
  }
  // The state before the first step, so a world started paused is seen (a viewer draws it).
  PublishGroundTruth();
  // A fault while building (a part's Configure, a transport's first Publish) under the stop
  // policy: the world is complete but takes no step; its caller saves and reports it.
  stopped_ = faults_.stop_requested();
}

void WorldImpl::PublishGroundTruth() {
  if (transports_.empty()) return;
  const WorldSnapshot truth = GroundTruth();
  for (auto& t : transports_) t->Guarded("Publish", [&](Transport& tr) { tr.Publish(truth); });
}

WorldImpl::~WorldImpl() {
  // Transports first: they may still post events from their threads until Stop joins them.
  for (auto& t : transports_) t->Stop();
  transports_.clear();
  held_.Release();
  robots_.clear();
  collision_.reset();
  scene_.reset();
  world_.reset();
}

void WorldImpl::Build() {
  const PhysicsModel& ph = model_.physics;
  world_.reset(dWorldCreate());
  dWorldID w = world_.get();
  dWorldSetGravity(w, ph.gravity.x(), ph.gravity.y(), ph.gravity.z());
  dWorldSetERP(w, ph.erp);
  dWorldSetCFM(w, ph.cfm);
  islands_.SetIterations(ph.solver_iterations, ph.IterationsWithoutBall());
  dWorldSetContactSurfaceLayer(w, ph.contact_surface_layer);
  dWorldSetContactMaxCorrectingVel(w, ph.contact_max_correcting_velocity);
  dWorldSetAutoDisableFlag(w, 0);  // a resting ball must react at once; also keeps runs exact

  scene_ = std::make_unique<SceneGraph>(w);
  body_ids_.clear();  // the old scene's: listed again at the first step
  body_ids_for_ = 0;
  collision_ = std::make_unique<CollisionManager>(*scene_, ParseBroadphase(ph.broadphase),
                                                  ph.max_contacts);
  const Broadphase broadphase = collision_->broadphase();
  islands_.SetMoveOrderMatters(broadphase == Broadphase::kSweepAndPrune || broadphase == Broadphase::kHash);
  // A body touching only the field keeps its contacts out of ODE: the islands' stepper steps
  // it, or makes them joints for QuickStep.
  collision_->StaticContacts().KeepStaticContacts(true);
  islands_.SetStaticContacts(&collision_->StaticContacts());
  for (const MaterialPair& p : model_.material_pairs) {
    collision_->materials().SetPair(p.a, p.b, p.surface);
  }
  // Above 2 ms a 6.5 m/s shot moves more than half the ball's radius per step: sweep it.
  collision_->SetSweptBallStep(ph.step);
  collision_->SetSweptRobotStep(ph.speculative_robot_contacts ? ph.step : 0.0);
  collision_->SetRobotContactErp(ph.robot_contact_erp.value_or(-1.0));
  collision_->SetStepAndErp(ph.step, ph.erp);

  NodeImpl& root = scene_->Root();
  BuildField(*model_.field, static_cast<NodeImpl&>(root.AddChild("field")));
  ball_ = &BuildBall(*model_.ball, model_.ball_start, static_cast<NodeImpl&>(root.AddChild("ball")));
  auto& blue = static_cast<NodeImpl&>(root.AddChild("blue"));
  auto& yellow = static_cast<NodeImpl&>(root.AddChild("yellow"));

  robot_services_holder_ = std::make_unique<RobotServices>();
  RobotServices& services = *robot_services_holder_;
  services.ball = ball_;
  services.ball_radius = model_.ball->radius;
  services.gravity = ph.gravity;
  services.sim_time_ns = &sim_time_ns_;
  services.faults = &faults_;
  services.last_good = &last_good_;
  services.materials = &collision_->materials();
  services.carpet = model_.field->carpet;
  team_nodes_[0] = &blue;
  team_nodes_[1] = &yellow;
  for (const RobotPlacement& base : roster_) {
    if (FindRobot(base.id)) {
      throw std::runtime_error(model_.file + ": robot " + ToString(base.id) + " is placed twice");
    }
    RobotPlacement p = base;
    p.model = EffectiveModel(base);
    robots_.push_back(std::make_unique<Robot>(p, p.id.team == Team::kBlue ? blue : yellow, registry_, log_, services));
  }
  last_good_.Track(scene_->Root());
}

const ModelLoader& WorldImpl::Loader() {
  if (!loader_) {
    loader_ = std::make_unique<ModelLoader>(ModelLoader::DefaultSchemaDir(), [this](PluginKind kind, const std::string& id) {
      return registry_.Find(kind, id).schema_json;
    });
  }
  return *loader_;
}

std::shared_ptr<const RobotModel> WorldImpl::EffectiveModel(const RobotPlacement& placement) {
  const auto key = std::make_pair(static_cast<int>(placement.id.team), placement.id.id);
  const auto spec = specs_.find(key);
  if (spec == specs_.end() || !placement.model) return placement.model;
  auto& cached = spec_models_[key];
  if (cached.first != placement.model || !cached.second) {
    SpecOutcome o = Loader().ApplySpec(*placement.model, spec->second);
    if (!o.model) {
      // Accepted for another base model; this one refuses it.
      log_.Warning("robot " + ToString(placement.id) + ": its robot specs do not fit model '" + placement.model->name +
                   "' (" + (o.errors.empty() ? std::string("?") : o.errors.front()) + "); built without them");
      return placement.model;
    }
    cached = {placement.model, o.model};
  }
  return cached.second;
}

std::shared_ptr<const RobotModel> WorldImpl::BaseModel(const RobotId& id) const {
  for (const RobotPlacement& p : roster_) {
    if (p.id == id) return p.model;
  }
  return model_.team_models[id.team == Team::kBlue ? 0 : 1];
}

Robot& WorldImpl::AddRobot(const RobotPlacement& base) {
  RobotPlacement p = base;
  p.model = EffectiveModel(base);
  NodeImpl& team = *team_nodes_[p.id.team == Team::kBlue ? 0 : 1];
  try {
    robots_.push_back(std::make_unique<Robot>(p, team, registry_, log_, *robot_services_holder_));
  } catch (...) {
    // What the robot built before it threw leaves with its node.
    if (NodeImpl* n = team.FindChildNode(std::to_string(p.id.id))) team.RemoveChild(*n);
    RobotsChanged();
    throw;
  }
  roster_.push_back(base);
  RobotsChanged();
  return *robots_.back();
}

void WorldImpl::RemoveRobot(const RobotId& id) {
  const auto it = std::find_if(robots_.begin(), robots_.end(), [&](const auto& r) { return r->id() == id; });
  if (it == robots_.end()) return;
  NodeImpl& node = (*it)->node();
  robots_.erase(it);  // its parts (plugin code) go while its bodies still exist
  node.parent()->RemoveChild(node);
  std::erase_if(roster_, [&](const RobotPlacement& p) { return p.id == id; });
  RobotsChanged();
}

void WorldImpl::RobotsChanged() {
  ++roster_version_;
  collision_->Refile();
  last_good_.Track(scene_->Root());
  body_ids_for_ = 0;  // the step's body list is made again
}

Robot* WorldImpl::ComeOn(const PositionEvent& e, EventAnswer& answer) {
  const RobotId& id = e.target.robot;
  const std::shared_ptr<const RobotModel> model = BaseModel(id);
  const double half_x = 0.5 * field_geometry_.carpet_length, half_y = 0.5 * field_geometry_.carpet_width;
  if (id.id < 0 || id.id > 15) {
    answer.errors.push_back("robot " + ToString(id) + ": robot ids are 0..15");
  } else if (!model) {
    answer.errors.push_back("robot " + ToString(id) + ": the world names no robot model for team " +
                            ToString(id.team) + " (teams." + ToString(id.team) + ".model)");
  } else if (!e.position) {
    answer.errors.push_back("robot " + ToString(id) + " is not in the world: a position is needed to put it on");
  } else if (std::abs(e.position->x()) > half_x || std::abs(e.position->y()) > half_y) {
    answer.errors.push_back("robot " + ToString(id) + ": (" + std::to_string(e.position->x()) + ", " +
                            std::to_string(e.position->y()) + ") m lies outside the walls");
  }
  if (!answer.errors.empty()) return nullptr;
  RobotPlacement p;
  p.id = id;
  p.model = model;
  p.x = e.position->x();
  p.y = e.position->y();
  p.yaw = e.yaw.value_or(id.team == Team::kBlue ? 0.0 : M_PI);
  try {
    Robot& r = AddRobot(p);
    log_.Info("robot " + ToString(id) + " came on (" + r.model().name + ")");
    return &r;
  } catch (const std::exception& ex) {
    answer.errors.push_back("robot " + ToString(id) + " could not be built: " + ExceptionText(ex));
  }
  return nullptr;
}

void WorldImpl::RebuildRobot(Robot& robot, EventAnswer& answer) {
  const RobotId id = robot.id();
  const Pose pose = robot.chassis().GetPose();
  const Twist twist = robot.chassis().GetTwist();
  const bool present = robot.present();
  RobotPlacement p;
  for (const RobotPlacement& r : roster_) {
    if (r.id == id) p = r;
  }
  p.x = pose.position.x();
  p.y = pose.position.y();
  p.yaw = pose.Yaw();
  p.present = present;
  RemoveRobot(id);
  Robot* built = nullptr;
  try {
    built = &AddRobot(p);
  } catch (const std::exception& ex) {
    answer.errors.push_back("robot " + ToString(id) + " could not be rebuilt: " + ExceptionText(ex));
  }
  if (!built) {
    specs_.erase({static_cast<int>(id.team), id.id});  // the robot as it was
    spec_models_.erase({static_cast<int>(id.team), id.id});
    built = &AddRobot(p);
  }
  built->SetVelocity(twist.linear, twist.angular);
  built->Placed();
}

void WorldImpl::Reset(std::uint64_t seed) {
  model_.seed = seed;
  perception_.Reset(seed);
  radio_.Reset(seed);
  Reset();
}

void WorldImpl::Reset() {
  roster_ = model_.robots;
  if (model_.field != initial_field_) UseField(initial_field_);
  Rebuild();
  log_.Info("world reset to " + model_.file);
  PublishGroundTruth();  // seen at once, also while paused
  stopped_ = faults_.stop_requested();
}

void WorldImpl::Rebuild() {
  held_.Release();  // its joint before the ODE world it is in
  hold_after_ns_ = 0;
  robots_.clear();
  islands_.SetStaticContacts(nullptr);  // the log goes with the collision manager
  collision_.reset();
  scene_.reset();
  world_.reset();
  pending_queries_.clear();
  repeated_.Clear();  // simulated time starts again
  clock_.Reset();
  sim_time_ns_ = 0;
  ode_random_seed_ = static_cast<unsigned long>(model_.seed);
  perception_.Reset();
  radio_.Reset();
  responses_lost_.clear();
  held_ball_ = model_.held_ball;
  faults_.Clear();
  stopped_ = false;
  faults_.SetNow(0, 0);
  Build();
}

namespace {
bool SpecIsEmpty(const RobotSpec& s) {
  return !(s.radius || s.height || s.mass || s.center_to_dribbler || s.max_flat_kick_speed || s.max_chip_kick_speed ||
           s.max_speed || s.max_angular_speed || s.max_acceleration || s.max_angular_acceleration ||
           s.max_deceleration || s.max_angular_deceleration || s.wheel_angles || s.dribbler_width);
}
}  // namespace

Robot* WorldImpl::FindRobot(const RobotId& id) const {
  std::size_t no_hint = robots_.size();
  return FindRobot(id, no_hint);
}

Robot* WorldImpl::FindRobot(const RobotId& id, std::size_t& hint) const {
  // A team's commands come robot after robot in one order, step after step: the robot after
  // the last one found is looked at first.
  if (hint < robots_.size() && robots_[hint]->id() == id) return robots_[hint++].get();
  for (std::size_t i = 0; i < robots_.size(); ++i) {
    if (robots_[i]->id() == id) {
      hint = i + 1;
      return robots_[i].get();
    }
  }
  return nullptr;
}

void WorldImpl::ProcessEvents() { ApplyEvents(false); }

void WorldImpl::ApplyEvents(bool stepping) {
  const std::uint64_t roster_before = roster_version_;
  events_.Drain(drained_);
  for (Event& e : drained_) {
    std::visit(
        [this](auto& ev) {
          using T = std::decay_t<decltype(ev)>;
          if constexpr (std::is_same_v<T, QueryEvent>) {
            pending_queries_.push_back(std::move(ev));
          } else if constexpr (std::is_same_v<T, CommandEvent>) {
            Apply(std::move(ev));  // drained_ is cleared below: the command itself goes on
          } else {
            Apply(ev);
          }
        },
        e);
  }
  drained_.clear();  // done with (their replies' captures go now); the storage is kept
  // Commands whose radio latency has passed reach their robots now.
  while (const CommandEvent* c = radio_.NextDue(sim_time_ns_)) {
    Deliver(*c);
    radio_.PopDue();
  }
  if (clock_control_.reset_requested) {
    clock_control_.reset_requested = false;
    Reset();
  }
  for (QueryEvent& q : pending_queries_) {
    if (q.reply) q.reply(Query(q.target));
  }
  pending_queries_.clear();
  // A robot that came on or was rebuilt while the world stands still is seen at once (a step
  // publishes anyway).
  if (!stepping && roster_version_ != roster_before) PublishGroundTruth();
}

void WorldImpl::Apply(const PositionEvent& e) {
  const bool finite = Finite(e.position) && Finite(e.velocity) && Finite(e.angular_velocity) &&
                      (!e.yaw || std::isfinite(*e.yaw));
  if (!finite) {
    ++event_counters_.rejected;
    log_.Warning("position event with non-finite values ignored");
    return;
  }
  // A teleport of the ball or of the robot holding it lets go of it.
  if (e.target.is_ball || (held_.holder() && e.target.robot == *held_.holder())) held_.Release();
  if (e.target.is_ball) {
    Pose p = ball_->GetPose();
    if (e.position) {
      p.position = *e.position;
      const double radius = model_.ball->radius;
      if (p.position.z() < radius) p.position.z() = radius;
      // A ball put into a robot or a wall goes to the nearest spot where it is free: deep inside,
      // its contacts would fire it out and strike the robot as hard (a ball put into a robot's
      // mouth at the wall spun the robot at 13 rad/s onto its side). A touch is left as put.
      const Eigen::Vector2d bounds(0.5 * field_geometry_.carpet_length - radius,
                                   0.5 * field_geometry_.carpet_width - radius);
      if (const auto free = collision_->FreeBallSpot(*ball_, p.position, kPlacedBallOverlap, kPlacedBallSearch, bounds)) {
        p.position = *free;
      } else {
        log_.Warning("ball put where it overlaps a robot or a wall, with no free spot within " +
                     std::to_string(kPlacedBallSearch) + " m: left there");
      }
    }
    ball_->SetPose(p);
    Twist t = ball_->GetTwist();
    if (e.velocity) t.linear = *e.velocity;
    if (e.angular_velocity) t.angular = *e.angular_velocity;
    if (e.position && !e.velocity) t = Twist{};  // a placed ball lies still unless told otherwise
    ball_->SetTwist(t);
    ++event_counters_.applied;
    return;
  }
  EventAnswer answer;
  const auto reply = [&] {
    if (e.reply) e.reply(answer);
  };
  Robot* r = FindRobot(e.target.robot);
  const bool on = e.present && *e.present;
  if (r && !r->present() && !on) {
    reply();  // off the field and not asked back on: nothing to move, as on grSim
    return;
  }
  if (!r) {
    // Not in the world: it comes on when asked to; otherwise nothing to move.
    if (on) r = ComeOn(e, answer);
    if (!r) {
      if (!answer.errors.empty()) {
        ++event_counters_.rejected;
        log_.Warning(answer.errors.front());
      }
      reply();
      return;
    }
  }
  if (e.present) r->SetPresent(*e.present);
  if (e.position || e.yaw) {
    const Pose p = r->chassis().GetPose();
    const double x = e.position ? e.position->x() : p.position.x();
    const double y = e.position ? e.position->y() : p.position.y();
    r->Teleport(x, y, e.yaw ? *e.yaw : p.Yaw());
  }
  if (e.velocity || e.angular_velocity) {
    const Twist t = r->chassis().GetTwist();
    Vec3 v = e.velocity ? *e.velocity : t.linear;
    if (e.position) {
      // Put down inside another robot: the part of its velocity into that robot would strike it
      // from inside; it is dropped (the contacts part the two).
      const Vec3 here = r->chassis().GetPose().position;
      for (const auto& other : robots_) {
        if (other.get() == r || !other->present()) continue;
        Vec3 to = other->chassis().GetPose().position - here;
        to.z() = 0.0;
        const double apart = to.norm();
        if (apart < 1e-9 || apart >= r->model().body.radius + other->model().body.radius) continue;
        const Vec3 n = to / apart;
        const double into = v.dot(n);
        if (into > 0.0) v -= into * n;
      }
    }
    r->SetVelocity(v, e.angular_velocity ? *e.angular_velocity : t.angular);
  } else if (e.position) {
    r->SetVelocity(Vec3::Zero(), Vec3::Zero());
  }
  if (e.position || e.yaw || e.velocity || e.angular_velocity) r->Placed();
  ++event_counters_.applied;
  reply();
}

void WorldImpl::Apply(CommandEvent&& e) {
  ++event_counters_.commands_received[e.robot.team == Team::kBlue ? 0 : 1];
  Robot* r = FindRobot(e.robot, sent_hint_);
  if (!r) {
    ++event_counters_.rejected;
    repeated_.Warn("unknown robot " + ToString(e.robot), "command for unknown robot " + ToString(e.robot) + " ignored",
                   sim_time_ns_);
    return;
  }
  bool finite = !e.dribbler_speed || std::isfinite(*e.dribbler_speed);
  if (e.kick) finite = finite && std::isfinite(e.kick->speed) && std::isfinite(e.kick->angle);
  if (e.move) {
    std::visit(
        [&](const auto& m) {
          using T = std::decay_t<decltype(m)>;
          if constexpr (std::is_same_v<T, WheelSpeedCommand>) {
            for (double w : m.wheel_speeds) finite = finite && std::isfinite(w);
          } else if constexpr (std::is_same_v<T, LocalVelocityCommand>) {
            finite = finite && std::isfinite(m.forward) && std::isfinite(m.left) &&
                     std::isfinite(m.angular);
          } else {
            finite = finite && std::isfinite(m.x) && std::isfinite(m.y) && std::isfinite(m.angular);
          }
        },
        *e.move);
  }
  if (!finite) {
    ++event_counters_.rejected;
    repeated_.Warn("non-finite command " + ToString(e.robot),
                   "command for robot " + ToString(e.robot) + " with non-finite values ignored", sim_time_ns_);
    return;
  }
  if (!radio_.Send(std::move(e), sim_time_ns_)) ++event_counters_.lost;
}

namespace {
// After a kick no dribbler holds the ball for this long (ER-Force's kicker recharges in 0.1 s):
// the kicked ball leaves the mouth instead of being caught again by the dribbler it left.
constexpr std::int64_t kKickedBallFreeNs = 100'000'000;
}  // namespace

void WorldImpl::UpdateHeldBall() {
  // A robot's own `dribbling:` over the world's.
  const auto holds = [this](const Robot& r) { return r.model().held_ball.value_or(held_ball_); };
  if (const std::optional<RobotId>& id = held_.holder()) {
    const Robot* r = FindRobot(*id);
    if (!r || !holds(*r) || !r->present() || r->dribbler_speed() <= 0) held_.Release();
    return;
  }
  if (sim_time_ns_ < hold_after_ns_) return;  // a kicked ball gets away first
  for (const auto& r : robots_) {
    if (holds(*r) && r->present() && r->dribbler_speed() > 0 && r->TouchesBall()) {
      held_.Attach(world_.get(), r->id(), r->chassis().id(), ball_->id());
      return;
    }
  }
}

void WorldImpl::Deliver(const CommandEvent& e) {
  // The holder lets go of the ball to kick it, or when its dribbler stops.
  if (held_.holder() == e.robot && (e.kick || (e.dribbler_speed && *e.dribbler_speed <= 0))) held_.Release();
  if (e.kick) hold_after_ns_ = sim_time_ns_ + kKickedBallFreeNs;
  Robot* r = FindRobot(e.robot, delivered_hint_);
  std::string why;
  if (r && r->Command(e, why)) {
    ++event_counters_.applied;
  } else {
    ++event_counters_.rejected;
    repeated_.Warn("refused command " + ToString(e.robot) + ": " + why,
                   "command for robot " + ToString(e.robot) + " partly refused: " + why, sim_time_ns_);
  }
}

void WorldImpl::Apply(const RealismEvent& e) {
  const std::optional<double> values[] = {e.vision_latency, e.ball_position_noise, e.robot_position_noise,
                                          e.robot_orientation_noise, e.ball_drop, e.robot_drop,
                                          e.camera_overlap, e.radio_latency, e.radio_loss,
                                          e.radio_response_loss, e.ball_visibility_threshold, e.ball_area_noise,
                                          e.dribbler_false_balls, e.camera_position_error, e.object_offset,
                                          e.processing_time};
  for (const auto& v : values) {
    if (v && (!std::isfinite(*v) || *v < 0)) {
      ++event_counters_.rejected;
      log_.Warning("realism settings must be finite and >= 0; ignored");
      return;
    }
  }
  for (const auto& p : {e.ball_drop, e.robot_drop, e.radio_loss, e.radio_response_loss, e.ball_visibility_threshold}) {
    if (p && *p > 1) {
      ++event_counters_.rejected;
      log_.Warning("a probability in the realism settings is above 1; ignored");
      return;
    }
  }
  PerceptionModel vision = perception_.model();
  if (e.vision_latency) vision.latency = *e.vision_latency;
  if (e.ball_position_noise) vision.ball_position_sigma = *e.ball_position_noise;
  if (e.robot_position_noise) vision.robot_position_sigma = *e.robot_position_noise;
  if (e.robot_orientation_noise) vision.robot_orientation_sigma = *e.robot_orientation_noise;
  if (e.ball_drop) vision.ball_drop = *e.ball_drop;
  if (e.robot_drop) vision.robot_drop = *e.robot_drop;
  if (e.camera_overlap) vision.camera_overlap = *e.camera_overlap;
  if (e.ball_occlusion) vision.ball_occlusion = *e.ball_occlusion;
  if (e.ball_visibility_threshold) vision.ball_visibility_threshold = *e.ball_visibility_threshold;
  if (e.ball_area_noise) vision.ball_area_sigma = *e.ball_area_noise;
  if (e.dribbler_false_balls) vision.dribbler_false_balls = *e.dribbler_false_balls;
  if (e.camera_position_error) vision.camera_position_error = *e.camera_position_error;
  if (e.object_offset) vision.object_offset = *e.object_offset;
  if (e.processing_time) vision.processing_time = *e.processing_time;
  perception_.Configure(vision);
  RadioModel radio = radio_.model();
  if (e.radio_latency) radio.latency = *e.radio_latency;
  if (e.radio_loss) radio.loss = *e.radio_loss;
  if (e.radio_response_loss) radio.response_loss = *e.radio_response_loss;
  radio_.Configure(radio);
  if (e.held_ball) held_ball_ = *e.held_ball;
  ++event_counters_.applied;
}

void WorldImpl::Apply(const RobotSpecEvent& e) {
  EventAnswer answer;
  const RobotId& id = e.robot;
  const std::shared_ptr<const RobotModel> base = BaseModel(id);
  if (id.id < 0 || id.id > 15) {
    answer.errors.push_back("robot " + ToString(id) + ": robot ids are 0..15");
  } else if (SpecIsEmpty(e.spec)) {
    // Nothing over the model: nothing to rebuild.
  } else if (!base) {
    answer.errors.push_back("robot " + ToString(id) + ": the world names no robot model for team " + ToString(id.team));
  } else {
    SpecOutcome o = Loader().ApplySpec(*base, e.spec);
    for (std::string& error : o.errors) answer.errors.push_back("robot " + ToString(id) + ": " + error);
    answer.unapplied = std::move(o.unmapped);
    const auto key = std::make_pair(static_cast<int>(id.team), id.id);
    const auto known = specs_.find(key);
    // A team announces its specs again and again (ssl-simulation-controller): the robot is
    // rebuilt only when they change.
    const bool same = known != specs_.end() && known->second == e.spec;
    if (o.model && !same) {
      specs_[key] = e.spec;
      spec_models_[key] = {base, o.model};
      if (Robot* r = FindRobot(id)) RebuildRobot(*r, answer);
    }
  }
  if (answer.errors.empty()) {
    ++event_counters_.applied;
  } else {
    ++event_counters_.rejected;
    log_.Warning("robot specs refused: " + answer.errors.front());
  }
  if (e.reply) e.reply(answer);
}

void WorldImpl::Apply(const FieldEvent& e) {
  // Sizes match to the millimetre the wire carries.
  const auto same = [](double a, double b) { return std::abs(a - b) < 0.0005; };
  const auto matches = [&](const FieldGeometry& g) {
    return same(e.field_length, g.field_length) && same(e.field_width, g.field_width) &&
           same(e.goal_width, g.goal_width) && same(e.goal_depth, g.goal_depth) &&
           same(e.boundary_width, g.boundary_width) &&
           (!e.penalty_area_depth || same(*e.penalty_area_depth, g.penalty_area_depth)) &&
           (!e.penalty_area_width || same(*e.penalty_area_width, g.penalty_area_width));
  };
  EventAnswer answer;
  std::shared_ptr<const FieldModel> target;
  std::string known;
  for (const auto& f : KnownFields()) {
    if (!target && matches(f->geometry)) target = f;
    char size[96];
    std::snprintf(size, sizeof size, "%s%s (%.3f × %.3f m)", known.empty() ? "" : ", ", f->geometry.name.c_str(),
                  f->geometry.field_length, f->geometry.field_width);
    known += size;
  }
  if (!target) {
    char asked[64];
    std::snprintf(asked, sizeof asked, "%.3f × %.3f m", e.field_length, e.field_width);
    answer.errors.push_back(std::string("no field of this world has the size asked for (") + asked + ", goal " +
                            std::to_string(e.goal_width) + " m); it knows " + known +
                            " (the world file's fields: list)");
    ++event_counters_.rejected;
  } else {
    if (target != model_.field) ChangeField(target);
    ++event_counters_.applied;
  }
  if (e.reply) e.reply(answer);
}

std::vector<std::shared_ptr<const FieldModel>> WorldImpl::KnownFields() const {
  std::vector<std::shared_ptr<const FieldModel>> out = {model_.field};
  for (const auto& f : model_.other_fields) {
    if (f->file != model_.field->file) out.push_back(f);
  }
  if (initial_field_ && initial_field_ != model_.field &&
      std::none_of(out.begin(), out.end(), [&](const auto& f) { return f->file == initial_field_->file; })) {
    out.push_back(initial_field_);
  }
  return out;
}

void WorldImpl::UseField(std::shared_ptr<const FieldModel> field) {
  model_.field = std::move(field);
  field_geometry_ = model_.field->geometry;  // in place: the transports hold a reference
  // As many cameras, as high, over the new carpet.
  perception_.SetCameras(CamerasOver(perception_.model().cameras, field_geometry_));
}

void WorldImpl::ChangeField(std::shared_ptr<const FieldModel> field) {
  const std::string from = model_.field->geometry.name;
  UseField(std::move(field));
  NodeImpl& root = scene_->Root();
  if (NodeImpl* old = root.FindChildNode("field")) root.RemoveChild(*old);
  BuildField(*model_.field, root.AddChildFirst("field"));
  // Everything stays where it was, inside the new walls.
  const double half_x = 0.5 * field_geometry_.carpet_length, half_y = 0.5 * field_geometry_.carpet_width;
  int moved = 0;
  for (const auto& r : robots_) {
    const Pose p = r->chassis().GetPose();
    const double margin = r->model().body.radius + 0.05;
    const double x = std::clamp(p.position.x(), -half_x + margin, half_x - margin);
    const double y = std::clamp(p.position.y(), -half_y + margin, half_y - margin);
    if (x != p.position.x() || y != p.position.y()) {
      r->Teleport(x, y, p.Yaw());
      r->SetVelocity(Vec3::Zero(), Vec3::Zero());
      r->Placed();
      ++moved;
    }
  }
  Pose ball = ball_->GetPose();
  const double m = model_.ball->radius + 0.05;
  if (std::abs(ball.position.x()) > half_x - m || std::abs(ball.position.y()) > half_y - m) {
    ball.position.x() = std::clamp(ball.position.x(), -half_x + m, half_x - m);
    ball.position.y() = std::clamp(ball.position.y(), -half_y + m, half_y - m);
    ball_->SetPose(ball);
    ball_->SetTwist(Twist{});
  }
  RobotsChanged();
  log_.Info("field changed from '" + from + "' to '" + field_geometry_.name + "'" +
            (moved ? " (" + std::to_string(moved) + " robots moved inside the new walls)" : std::string()));
}

void WorldImpl::Apply(const TransportSettingEvent& e) {
  EventAnswer answer;
  bool taken = false;
  for (auto& t : transports_) {
    std::string refusal;
    taken = t->OnSetting(e.name, e.value, refusal) || taken;
    if (!refusal.empty()) answer.errors.push_back(refusal);
  }
  if (!taken && answer.errors.empty()) {
    answer.errors.push_back("no transport of this world takes the setting '" + e.name + "'");
  }
  if (answer.errors.empty()) {
    ++event_counters_.applied;
  } else {
    ++event_counters_.rejected;
  }
  if (e.reply) e.reply(answer);
}

void WorldImpl::Apply(const ClockEvent& e) {
  switch (e.action) {
    case ClockEvent::Action::kPause: clock_control_.paused = true; break;
    case ClockEvent::Action::kResume: clock_control_.paused = false; break;
    case ClockEvent::Action::kStep:
      clock_control_.paused = true;
      clock_control_.pending_steps += std::max(0, e.steps);
      break;
    case ClockEvent::Action::kSetSpeed:
      if (!std::isfinite(e.speed_factor) || e.speed_factor < 0) {
        ++event_counters_.rejected;
        log_.Warning("speed factor must be finite and >= 0; ignored");
        return;
      }
      clock_control_.speed_factor = e.speed_factor;
      break;
    case ClockEvent::Action::kReset: clock_control_.reset_requested = true; break;
  }
  ++event_counters_.applied;
}

ObjectState WorldImpl::Query(const Target& t) const {
  ObjectState s;
  if (t.is_ball) {
    s.found = true;
    s.pose = ball_->GetPose();
    s.twist = ball_->GetTwist();
    return s;
  }
  if (Robot* r = FindRobot(t.robot)) {
    s.found = true;
    s.present = r->present();
    s.pose = r->chassis().GetPose();
    s.twist = r->chassis().GetTwist();
  }
  return s;
}

void WorldImpl::Step() {
  if (stopped_) return;
  faults_.SetNow(clock_.steps(), clock_.time_ns());
  // Whatever touched the bodies since the last step (nothing should) is not the fault of the
  // plugin called next: repaired here, each plugin call then answers for itself.
  if (!last_good_.AllFinite()) RepairNonFinite("before the step");
  auto t0 = SteadyClock::now();
  for (auto& t : transports_) t->Guarded("Poll", [](Transport& tr) { tr.Poll(); });
  timings_.transports_ns += ElapsedNs(t0);

  t0 = SteadyClock::now();
  ApplyEvents(true);
  timings_.events_ns += ElapsedNs(t0);

  const StepInfo info{clock_.steps(), clock_.step_seconds(), clock_.time_ns()};
  t0 = SteadyClock::now();
  for (auto& r : robots_) r->PreStep(info);
  timings_.plugins_ns += ElapsedNs(t0);

  t0 = SteadyClock::now();
  collision_->Collide();
  timings_.collision_ns += ElapsedNs(t0);

  t0 = SteadyClock::now();
  // ODE's QuickStep draws from one process-wide generator; each world keeps its own sequence.
  dRandSetSeed(ode_random_seed_);
  if (scene_->bodies_created() != body_ids_for_) {
    // Newest first, ODE's own order: the lone bodies are then stepped in QuickStep's order.
    std::vector<const BodyImpl*> by_age;
    scene_->Root().ForEachBody([&by_age](BodyImpl& b) { by_age.push_back(&b); });
    std::sort(by_age.begin(), by_age.end(), [](const BodyImpl* x, const BodyImpl* y) { return x->serial() > y->serial(); });
    body_ids_.clear();
    for (const BodyImpl* b : by_age) body_ids_.push_back(b->id());
    limbs_ = FindLimbs(body_ids_);  // the plugins add a robot's bodies and joints together
    body_ids_for_ = scene_->bodies_created();
  }
  ball_ids_.assign(1, ball_->id());
  iteration_demands_.clear();
  for (const auto& r : robots_) {
    const int wanted = r->model().min_solver_iterations;
    if (wanted > 0 && r->present()) iteration_demands_.push_back({r->chassis().id(), wanted});
  }
  // Robots pushing or crashing into each other are solved as the ball's islands are: with two
  // sweeps a push converges too loosely and the robots sink into each other.
  for (dBodyID chassis : collision_->RobotsInContact()) {
    iteration_demands_.push_back({chassis, model_.physics.solver_iterations});
  }
  islands_.Step(world_.get(), body_ids_, ball_ids_, clock_.step_seconds(), limbs_, iteration_demands_);
  ode_random_seed_ = dRandGetSeed();
  collision_->ClearContacts();
  timings_.physics_ns += ElapsedNs(t0);
  clock_.Advance();
  sim_time_ns_ = clock_.time_ns();

  const StepInfo after{info.step, info.dt, clock_.time_ns()};
  t0 = SteadyClock::now();
  for (auto& r : robots_) r->PostStep(after);
  UpdateHeldBall();
  timings_.plugins_ns += ElapsedNs(t0);
  // The last good state, or the repair when something went non-finite nonetheless.
  if (!last_good_.CaptureIfFinite()) {
    RepairNonFinite("after the physics step");
    last_good_.CaptureIfFinite();
  }

  // One ground truth serves the cameras and the transports, and is taken only when one needs it.
  // Cameras alone (a batch or a bench run) need no part's report: the drives' feedback was half
  // of a snapshot's work.
  std::optional<WorldSnapshot> truth;
  t0 = SteadyClock::now();
  responses_lost_ = radio_.ResponsesLost(robots_.size());
  if (perception_.CaptureDue(sim_time_ns_)) {
    truth = transports_.empty() ? Kinematics() : GroundTruth();
    perception_.Capture(*truth, FrontDistances(*truth));
  }
  const std::vector<VisionFrame> frames = perception_.Release(sim_time_ns_);
  timings_.perception_ns += ElapsedNs(t0);

  t0 = SteadyClock::now();
  for (const VisionFrame& f : frames) {
    if (vision_observer_) vision_observer_(f);
    for (auto& t : transports_) t->Guarded("OnVisionFrame", [&](Transport& tr) { tr.OnVisionFrame(f); });
  }
  if (!transports_.empty()) {
    if (!truth) truth = GroundTruth();
    for (auto& t : transports_) {
      t->Guarded("Publish", [&](Transport& tr) { tr.Publish(*truth); });
    }
  }
  timings_.transports_ns += ElapsedNs(t0);
  // Under the stop policy a fault in this step ends the run here, with the step complete.
  if (faults_.stop_requested()) stopped_ = true;
}

void WorldImpl::RepairNonFinite(const char* when) {
  // The kernel's state checks name what went non-finite: a robot (its bodies are its own, so it
  // is reported and repaired as one) or the ball.
  StateCheckOptions finite_only;
  finite_only.speed = finite_only.carpet = finite_only.walls = finite_only.overlap = false;
  for (const StateViolation& v : CheckState(*this, finite_only)) {
    Robot* robot = v.object.kind == StateObject::Kind::kRobot ? FindRobot(v.object.robot) : nullptr;
    if (robot) {
      robot->RepairNonFinite(when, clock_.steps(), v.Describe());
      continue;
    }
    PluginFault fault;
    fault.phase = when;
    fault.what = v.Describe();
    faults_.Report(std::move(fault));
  }
  kernel::RepairNonFinite(scene_->Root(), last_good_);
}

WorldSnapshot WorldImpl::GroundTruth() const { return Snapshot(true); }
WorldSnapshot WorldImpl::Kinematics() const { return Snapshot(false); }

std::vector<double> WorldImpl::FrontDistances(const WorldSnapshot& truth) const {
  // Only the occlusion of the ball and the false balls at dribblers need the robots' fronts.
  const PerceptionModel& vision = perception_.model();
  if (!vision.ball_occlusion && vision.dribbler_false_balls <= 0) return {};
  std::vector<double> out;
  out.reserve(truth.robots.size());
  for (const RobotState& r : truth.robots) {
    const Robot* robot = FindRobot(r.id);
    out.push_back(robot ? robot->model().body.front_distance : r.radius);
  }
  return out;
}

WorldSnapshot WorldImpl::Snapshot(bool parts) const {
  WorldSnapshot s;
  s.step = clock_.steps();
  s.sim_time_ns = clock_.time_ns();
  s.ball.pose = ball_->GetPose();
  s.ball.twist = ball_->GetTwist();
  s.ball.radius = model_.ball->radius;
  // Built in place: a state moved into the list and the moved-from one destroyed cost more
  // than filling it (a snapshot is taken every other step, for the cameras and for the teams).
  s.robots.resize(robots_.size());
  for (std::size_t i = 0; i < robots_.size(); ++i) {
    RobotState& r = s.robots[i];
    if (parts) {
      r = robots_[i]->State();
    } else {
      robots_[i]->WriteKinematics(r);
    }
    r.feedback_lost = i < responses_lost_.size() && responses_lost_[i];
  }
  // Blue first, then yellow, each by id (robots that came on later are last in robots_). Most
  // snapshots find them in that order already: checked first, since sorting moves whole states.
  const auto before = [](const RobotState& a, const RobotState& b) {
    return a.id.team != b.id.team ? a.id.team == Team::kBlue : a.id.id < b.id.id;
  };
  if (!std::is_sorted(s.robots.begin(), s.robots.end(), before)) std::sort(s.robots.begin(), s.robots.end(), before);
  s.field = &field_geometry_;
  return s;
}

std::uint64_t WorldImpl::StateHash() const {
  std::uint64_t h = kFnv1aOffset;
  const std::int64_t steps = clock_.steps();
  Fnv1a(h, &steps, sizeof steps);
  scene_->Root().ForEachBody([&](BodyImpl& b) {
    const dBodyID id = b.id();
    Fnv1a(h, dBodyGetPosition(id), 3 * sizeof(dReal));
    Fnv1a(h, dBodyGetQuaternion(id), 4 * sizeof(dReal));
    Fnv1a(h, dBodyGetLinearVel(id), 3 * sizeof(dReal));
    Fnv1a(h, dBodyGetAngularVel(id), 3 * sizeof(dReal));
  });
  return h;
}

std::vector<std::string> WorldImpl::TransportEndpoints() const {
  std::vector<std::string> out;
  for (const auto& t : transports_) out.push_back(t->Endpoint());
  return out;
}

}  // namespace ubersim::kernel
