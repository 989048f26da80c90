// SPDX-License-Identifier: Apache-2.0
#include "ubersim/kernel/snapshot.hpp"

#include "util/fnv1a.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>

#include "ubersim_snapshot.pb.h"

namespace ubersim::kernel {
namespace {

namespace pb = ubersim::snapshot;

constexpr char kMagic[] = "ubersim-snapshot";
constexpr std::uint32_t kFormatVersion = 1;
// A world's snapshot is tens to hundreds of kilobytes; anything this large is not one, and is
// refused before it is read into memory.
constexpr std::uintmax_t kMaxFileBytes = 256u << 20;

std::uint32_t Crc32(std::string_view data) {
  static const std::array<std::uint32_t, 256> table = [] {
    std::array<std::uint32_t, 256> t{};
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  std::uint32_t c = 0xFFFFFFFFu;
  for (unsigned char b : data) c = table[(c ^ b) & 0xFFu] ^ (c >> 8);
  return c ^ 0xFFFFFFFFu;
}

template <typename Array>
void Put(const Array& a, google::protobuf::RepeatedField<double>* out) {
  out->Reserve(static_cast<int>(a.size()));
  for (double v : a) out->Add(v);
}

template <std::size_t N>
void Get(const google::protobuf::RepeatedField<double>& in, std::array<double, N>& out, const std::string& what) {
  if (in.size() != static_cast<int>(N)) {
    throw SnapshotError(what + " has " + std::to_string(in.size()) + " values instead of " + std::to_string(N));
  }
  std::copy(in.begin(), in.end(), out.begin());
}

// The RobotSpec fields with the proto's accessors, in one table for both directions.
template <typename F>
void ForEachSpecField(F&& f) {
  f(&RobotSpec::radius, &pb::RobotSpec::has_radius, &pb::RobotSpec::radius, &pb::RobotSpec::set_radius);
  f(&RobotSpec::height, &pb::RobotSpec::has_height, &pb::RobotSpec::height, &pb::RobotSpec::set_height);
  f(&RobotSpec::mass, &pb::RobotSpec::has_mass, &pb::RobotSpec::mass, &pb::RobotSpec::set_mass);
  f(&RobotSpec::center_to_dribbler, &pb::RobotSpec::has_center_to_dribbler, &pb::RobotSpec::center_to_dribbler,
    &pb::RobotSpec::set_center_to_dribbler);
  f(&RobotSpec::max_flat_kick_speed, &pb::RobotSpec::has_max_flat_kick_speed, &pb::RobotSpec::max_flat_kick_speed,
    &pb::RobotSpec::set_max_flat_kick_speed);
  f(&RobotSpec::max_chip_kick_speed, &pb::RobotSpec::has_max_chip_kick_speed, &pb::RobotSpec::max_chip_kick_speed,
    &pb::RobotSpec::set_max_chip_kick_speed);
  f(&RobotSpec::max_speed, &pb::RobotSpec::has_max_speed, &pb::RobotSpec::max_speed, &pb::RobotSpec::set_max_speed);
  f(&RobotSpec::max_angular_speed, &pb::RobotSpec::has_max_angular_speed, &pb::RobotSpec::max_angular_speed,
    &pb::RobotSpec::set_max_angular_speed);
  f(&RobotSpec::max_acceleration, &pb::RobotSpec::has_max_acceleration, &pb::RobotSpec::max_acceleration,
    &pb::RobotSpec::set_max_acceleration);
  f(&RobotSpec::max_angular_acceleration, &pb::RobotSpec::has_max_angular_acceleration,
    &pb::RobotSpec::max_angular_acceleration, &pb::RobotSpec::set_max_angular_acceleration);
  f(&RobotSpec::max_deceleration, &pb::RobotSpec::has_max_deceleration, &pb::RobotSpec::max_deceleration,
    &pb::RobotSpec::set_max_deceleration);
  f(&RobotSpec::max_angular_deceleration, &pb::RobotSpec::has_max_angular_deceleration,
    &pb::RobotSpec::max_angular_deceleration, &pb::RobotSpec::set_max_angular_deceleration);
  f(&RobotSpec::dribbler_width, &pb::RobotSpec::has_dribbler_width, &pb::RobotSpec::dribbler_width,
    &pb::RobotSpec::set_dribbler_width);
}

void PutSpec(const RobotSpec& in, pb::RobotSpec& out) {
  ForEachSpecField([&](auto field, auto, auto, auto set) {
    if (in.*field) (out.*set)(*(in.*field));
  });
  if (in.wheel_angles) {
    out.set_has_wheel_angles(true);
    for (double a : *in.wheel_angles) out.add_wheel_angles(a);
  }
}

RobotSpec GetSpec(const pb::RobotSpec& in) {
  RobotSpec out;
  ForEachSpecField([&](auto field, auto has, auto get, auto) {
    if ((in.*has)()) out.*field = (in.*get)();
  });
  if (in.has_wheel_angles()) out.wheel_angles.emplace(in.wheel_angles().begin(), in.wheel_angles().end());
  return out;
}

Team TeamOf(std::uint32_t v, const std::string& what) {
  if (v > 1) throw SnapshotError(what + ": team " + std::to_string(v) + " is neither blue (0) nor yellow (1)");
  return static_cast<Team>(v);
}

PluginKind KindOf(std::uint32_t v, const std::string& what) {
  if (v < 1 || v > 4) throw SnapshotError(what + ": unknown plugin kind " + std::to_string(v));
  return static_cast<PluginKind>(v);
}

void PutCommand(const CommandEvent& c, pb::Command* out) {
  out->set_team(static_cast<std::uint32_t>(c.robot.team));
  out->set_id(c.robot.id);
  if (c.move) {
    if (const auto* w = std::get_if<WheelSpeedCommand>(&*c.move)) {
      for (double s : w->wheel_speeds) out->mutable_wheel_speeds()->add_speeds(s);
      out->mutable_wheel_speeds();  // present even with no wheels
    } else if (const auto* l = std::get_if<LocalVelocityCommand>(&*c.move)) {
      pb::Velocity* v = out->mutable_local_velocity();
      v->set_a(l->forward);
      v->set_b(l->left);
      v->set_angular(l->angular);
    } else if (const auto* g = std::get_if<GlobalVelocityCommand>(&*c.move)) {
      pb::Velocity* v = out->mutable_global_velocity();
      v->set_a(g->x);
      v->set_b(g->y);
      v->set_angular(g->angular);
    }
  }
  out->set_has_kick(c.kick.has_value());
  if (c.kick) {
    out->set_kick_speed(c.kick->speed);
    out->set_kick_angle(c.kick->angle);
  }
  out->set_has_dribbler_speed(c.dribbler_speed.has_value());
  if (c.dribbler_speed) out->set_dribbler_speed(*c.dribbler_speed);
}

CommandEvent GetCommand(const pb::Command& in) {
  CommandEvent c;
  c.robot = RobotId{TeamOf(in.team(), "a queued command"), in.id()};
  switch (in.move_case()) {
    case pb::Command::kWheelSpeeds: {
      WheelSpeedCommand w;
      w.wheel_speeds.assign(in.wheel_speeds().speeds().begin(), in.wheel_speeds().speeds().end());
      c.move = w;
      break;
    }
    case pb::Command::kLocalVelocity:
      c.move = LocalVelocityCommand{in.local_velocity().a(), in.local_velocity().b(), in.local_velocity().angular()};
      break;
    case pb::Command::kGlobalVelocity:
      c.move = GlobalVelocityCommand{in.global_velocity().a(), in.global_velocity().b(), in.global_velocity().angular()};
      break;
    default: break;
  }
  if (in.has_kick()) c.kick = KickCommand{in.kick_speed(), in.kick_angle()};
  if (in.has_dribbler_speed()) c.dribbler_speed = in.dribbler_speed();
  return c;
}

void PutFrame(const VisionFrame& f, pb::VisionFrame* out) {
  out->set_camera_id(f.camera_id);
  out->set_frame_number(f.frame_number);
  out->set_t_capture_ns(f.t_capture_ns);
  out->set_t_sent_ns(f.t_sent_ns);
  for (const DetectedBall& b : f.balls) {
    pb::DetectedBall* o = out->add_balls();
    o->set_x(b.x);
    o->set_y(b.y);
    o->set_z(b.z);
    o->set_confidence(b.confidence);
    o->set_area(b.area);
  }
  for (const DetectedRobot& r : f.robots) {
    pb::DetectedRobot* o = out->add_robots();
    o->set_team(static_cast<std::uint32_t>(r.id.team));
    o->set_id(r.id.id);
    o->set_x(r.x);
    o->set_y(r.y);
    o->set_yaw(r.yaw);
    o->set_confidence(r.confidence);
  }
}

VisionFrame GetFrame(const pb::VisionFrame& in) {
  VisionFrame f;
  f.camera_id = in.camera_id();
  f.frame_number = in.frame_number();
  f.t_capture_ns = in.t_capture_ns();
  f.t_sent_ns = in.t_sent_ns();
  for (const pb::DetectedBall& b : in.balls()) f.balls.push_back(DetectedBall{b.x(), b.y(), b.z(), b.confidence(), b.area()});
  for (const pb::DetectedRobot& r : in.robots()) {
    DetectedRobot d;
    d.id = RobotId{TeamOf(r.team(), "a vision frame"), r.id()};
    d.x = r.x();
    d.y = r.y();
    d.yaw = r.yaw();
    d.confidence = r.confidence();
    f.robots.push_back(d);
  }
  return f;
}

void PutState(const SavedState& s, pb::WorldState& out) {
  out.set_world_name(s.world_name);
  out.set_world_file(s.world_file);
  out.set_field_file(s.field_file);
  out.set_structure(s.structure);
  for (const ModelFileDigest& m : s.model_files) {
    pb::ModelFile* o = out.add_model_files();
    o->set_path(m.path);
    o->set_digest(m.digest);
  }
  out.set_ubersim_version(s.ubersim_version);
  out.set_created_utc(s.created_utc);
  out.set_step(s.step);
  out.set_time_ns(s.time_ns);
  out.set_step_ns(s.step_ns);
  out.set_ode_random_seed(s.ode_random_seed);
  for (const SavedBody& b : s.bodies) {
    pb::Body* o = out.add_bodies();
    o->set_path(b.path);
    Put(b.position, o->mutable_position());
    Put(b.quaternion, o->mutable_quaternion());
    Put(b.rotation, o->mutable_rotation());
    Put(b.linear_velocity, o->mutable_linear_velocity());
    Put(b.angular_velocity, o->mutable_angular_velocity());
    Put(b.force, o->mutable_force());
    Put(b.torque, o->mutable_torque());
    o->set_enabled(b.enabled);
  }
  for (const SavedJoint& j : s.joints) {
    pb::Joint* o = out.add_joints();
    o->set_path(j.path);
    o->set_motor_velocity(j.motor_velocity);
    o->set_motor_max_effort(j.motor_max_effort);
    Put(j.feedback, o->mutable_feedback());
  }
  std::string collides;
  for (bool c : s.geom_collides) collides.push_back(c ? '\1' : '\0');
  out.set_geom_collides(collides);
  for (std::uint32_t i : s.moved_bodies) out.add_moved_bodies(i);
  for (const SavedRobot& r : s.robots) {
    pb::Robot* o = out.add_robots();
    o->set_team(static_cast<std::uint32_t>(r.id.team));
    o->set_id(r.id.id);
    o->set_present(r.present);
    o->set_model_file(r.model_file);
    if (r.built_at) {
      o->set_has_built_at(true);
      o->set_built_x((*r.built_at)[0]);
      o->set_built_y((*r.built_at)[1]);
      o->set_built_yaw((*r.built_at)[2]);
    }
    for (const SavedPart& p : r.parts) {
      pb::Part* q = o->add_parts();
      q->set_kind(static_cast<std::uint32_t>(p.kind));
      q->set_plugin(p.plugin);
      q->set_version(p.version);
      q->set_failed(p.failed);
      q->set_state(p.state);
    }
  }
  const PerceptionState& v = s.perception;
  pb::Perception* po = out.mutable_perception();
  po->set_latency(v.model.latency);
  po->set_ball_position_sigma(v.model.ball_position_sigma);
  po->set_robot_position_sigma(v.model.robot_position_sigma);
  po->set_robot_orientation_sigma(v.model.robot_orientation_sigma);
  po->set_ball_drop(v.model.ball_drop);
  po->set_robot_drop(v.model.robot_drop);
  po->set_camera_overlap(v.model.camera_overlap);
  po->set_ball_occlusion(v.model.ball_occlusion);
  po->set_ball_visibility_threshold(v.model.ball_visibility_threshold);
  po->set_ball_area_sigma(v.model.ball_area_sigma);
  po->set_dribbler_false_balls(v.model.dribbler_false_balls);
  po->set_camera_position_error(v.model.camera_position_error);
  po->set_object_offset(v.model.object_offset);
  po->set_has_processing_time(v.model.processing_time.has_value());
  po->set_processing_time(v.model.processing_time.value_or(0.0));
  for (std::int64_t t : v.next_capture_ns) po->add_next_capture_ns(t);
  for (std::uint32_t n : v.frame_numbers) po->add_frame_numbers(n);
  for (const VisionFrame& f : v.in_flight) PutFrame(f, po->add_in_flight());
  po->set_rng(v.rng);
  out.set_held_ball(s.held_ball);
  out.set_ball_held(s.ball_held_by.has_value());
  if (s.ball_held_by) {
    out.set_held_team(static_cast<std::uint32_t>(s.ball_held_by->team));
    out.set_held_id(s.ball_held_by->id);
  }
  pb::Radio* ro = out.mutable_radio();
  ro->set_latency(s.radio.model.latency);
  ro->set_loss(s.radio.model.loss);
  ro->set_response_loss(s.radio.model.response_loss);
  for (const auto& [due, command] : s.radio.queue) {
    ro->add_due_ns(due);
    PutCommand(command, ro->add_queue());
  }
  ro->set_rng(s.radio.rng);
  for (const PluginFault& f : s.faults) {
    pb::Fault* o = out.add_faults();
    o->set_has_robot(f.robot.has_value());
    if (f.robot) {
      o->set_team(static_cast<std::uint32_t>(f.robot->team));
      o->set_id(f.robot->id);
    }
    o->set_kind(static_cast<std::uint32_t>(f.kind));
    o->set_plugin(f.plugin);
    o->set_file(f.file);
    o->set_phase(f.phase);
    o->set_what(f.what);
    o->set_step(f.step);
    o->set_sim_time_ns(f.sim_time_ns);
  }
  for (const auto& [id, spec] : s.robot_specs) {
    pb::AnnouncedSpec* o = out.add_robot_specs();
    o->set_team(static_cast<std::uint32_t>(id.team));
    o->set_id(id.id);
    PutSpec(spec, *o->mutable_spec());
  }
}

SavedState GetState(const pb::WorldState& in) {
  SavedState s;
  s.world_name = in.world_name();
  s.world_file = in.world_file();
  s.field_file = in.field_file();
  s.structure = in.structure();
  for (const pb::ModelFile& m : in.model_files()) s.model_files.push_back(ModelFileDigest{m.path(), m.digest()});
  s.ubersim_version = in.ubersim_version();
  s.created_utc = in.created_utc();
  s.step = in.step();
  s.time_ns = in.time_ns();
  s.step_ns = in.step_ns();
  s.ode_random_seed = in.ode_random_seed();
  if (s.step < 0 || s.time_ns < 0 || s.step_ns <= 0) {
    throw SnapshotError("its clock is impossible (step " + std::to_string(s.step) + ", time " +
                        std::to_string(s.time_ns) + " ns, step length " + std::to_string(s.step_ns) + " ns)");
  }
  for (const pb::Body& b : in.bodies()) {
    SavedBody o;
    o.path = b.path();
    const std::string what = "body '" + b.path() + "'";
    Get(b.position(), o.position, what + " position");
    Get(b.quaternion(), o.quaternion, what + " quaternion");
    Get(b.rotation(), o.rotation, what + " rotation");
    Get(b.linear_velocity(), o.linear_velocity, what + " linear velocity");
    Get(b.angular_velocity(), o.angular_velocity, what + " angular velocity");
    Get(b.force(), o.force, what + " force");
    Get(b.torque(), o.torque, what + " torque");
    o.enabled = b.enabled();
    s.bodies.push_back(std::move(o));
  }
  for (const pb::Joint& j : in.joints()) {
    SavedJoint o;
    o.path = j.path();
    o.motor_velocity = j.motor_velocity();
    o.motor_max_effort = j.motor_max_effort();
    Get(j.feedback(), o.feedback, "joint '" + j.path() + "' feedback");
    s.joints.push_back(std::move(o));
  }
  for (char c : in.geom_collides()) {
    if (c != '\0' && c != '\1') throw SnapshotError("a geometry's collision flag is neither 0 nor 1");
    s.geom_collides.push_back(c == '\1');
  }
  s.moved_bodies.assign(in.moved_bodies().begin(), in.moved_bodies().end());
  for (const pb::Robot& r : in.robots()) {
    SavedRobot o;
    o.id = RobotId{TeamOf(r.team(), "a robot"), r.id()};
    o.present = r.present();
    o.model_file = r.model_file();
    if (r.has_built_at()) o.built_at = std::array<double, 3>{r.built_x(), r.built_y(), r.built_yaw()};
    for (const pb::Part& p : r.parts()) {
      o.parts.push_back(SavedPart{KindOf(p.kind(), "a robot part"), p.plugin(), p.version(), p.failed(), p.state()});
    }
    s.robots.push_back(std::move(o));
  }
  const pb::Perception& po = in.perception();
  PerceptionModel& vm = s.perception.model;
  vm.latency = po.latency();
  vm.ball_position_sigma = po.ball_position_sigma();
  vm.robot_position_sigma = po.robot_position_sigma();
  vm.robot_orientation_sigma = po.robot_orientation_sigma();
  vm.ball_drop = po.ball_drop();
  vm.robot_drop = po.robot_drop();
  vm.camera_overlap = po.camera_overlap();
  vm.ball_occlusion = po.ball_occlusion();
  vm.ball_visibility_threshold = po.ball_visibility_threshold();
  vm.ball_area_sigma = po.ball_area_sigma();
  vm.dribbler_false_balls = po.dribbler_false_balls();
  vm.camera_position_error = po.camera_position_error();
  vm.object_offset = po.object_offset();
  if (po.has_processing_time()) vm.processing_time = po.processing_time();
  s.perception.next_capture_ns.assign(po.next_capture_ns().begin(), po.next_capture_ns().end());
  s.perception.frame_numbers.assign(po.frame_numbers().begin(), po.frame_numbers().end());
  for (const pb::VisionFrame& f : po.in_flight()) s.perception.in_flight.push_back(GetFrame(f));
  s.perception.rng = po.rng();
  s.held_ball = in.held_ball();
  if (in.ball_held()) s.ball_held_by = RobotId{in.held_team() == 0 ? Team::kBlue : Team::kYellow, in.held_id()};
  const pb::Radio& ro = in.radio();
  s.radio.model.latency = ro.latency();
  s.radio.model.loss = ro.loss();
  s.radio.model.response_loss = ro.response_loss();
  if (ro.due_ns_size() != ro.queue_size()) throw SnapshotError("the radio queue's times and commands differ in number");
  for (int i = 0; i < ro.queue_size(); ++i) s.radio.queue.emplace_back(ro.due_ns(i), GetCommand(ro.queue(i)));
  s.radio.rng = ro.rng();
  for (const pb::Fault& f : in.faults()) {
    PluginFault o;
    if (f.has_robot()) o.robot = RobotId{TeamOf(f.team(), "a fault"), f.id()};
    o.kind = KindOf(f.kind(), "a fault");
    o.plugin = f.plugin();
    o.file = f.file();
    o.phase = f.phase();
    o.what = f.what();
    o.step = f.step();
    o.sim_time_ns = f.sim_time_ns();
    s.faults.push_back(std::move(o));
  }
  for (const pb::AnnouncedSpec& a : in.robot_specs()) {
    s.robot_specs.emplace_back(RobotId{TeamOf(a.team(), "robot specs"), a.id()}, GetSpec(a.spec()));
  }
  return s;
}

}  // namespace

std::string EncodeSnapshot(const SavedState& state) {
  pb::WorldState world;
  PutState(state, world);
  pb::SnapshotFile file;
  file.set_magic(kMagic);
  file.set_format_version(kFormatVersion);
  if (!world.SerializeToString(file.mutable_state())) throw SnapshotError("the state could not be serialised");
  file.set_crc32(Crc32(file.state()));
  file.set_state_size(file.state().size());
  std::string out;
  if (!file.SerializeToString(&out)) throw SnapshotError("the snapshot could not be serialised");
  return out;
}

SavedState DecodeSnapshot(std::string_view bytes, const std::string& source) {
  const auto fail = [&](const std::string& why) { return SnapshotError(source + ": " + why); };
  if (bytes.empty()) throw fail("empty file, not an ÜberSim snapshot");
  if (bytes.size() > std::numeric_limits<int>::max()) throw fail("too large to be an ÜberSim snapshot");
  // How a snapshot file begins: field 1, a 16-byte string, the magic.
  const std::string start = std::string("\x0a\x10") + kMagic;
  const bool starts_right = bytes.substr(0, start.size()) == start;
  pb::SnapshotFile file;
  if (!file.ParseFromArray(bytes.data(), static_cast<int>(bytes.size())) || file.magic() != kMagic) {
    throw fail(starts_right ? "truncated or damaged: it does not parse" : "not an ÜberSim snapshot");
  }
  if (file.format_version() != kFormatVersion) {
    throw fail("snapshot format " + std::to_string(file.format_version()) + "; this ubersim reads format " +
               std::to_string(kFormatVersion));
  }
  if (file.state_size() != file.state().size()) {
    throw fail("truncated: the state has " + std::to_string(file.state().size()) + " of its " +
               std::to_string(file.state_size()) + " bytes");
  }
  if (Crc32(file.state()) != file.crc32()) throw fail("corrupt: its checksum does not match its contents");
  pb::WorldState world;
  if (!world.ParseFromString(file.state())) throw fail("corrupt: the state does not parse");
  try {
    return GetState(world);
  } catch (const SnapshotError& e) {
    throw fail(std::string("inconsistent: ") + e.what());
  }
}

void WriteSnapshotFile(const std::filesystem::path& file, const SavedState& state) {
  const std::string bytes = EncodeSnapshot(state);
  const std::filesystem::path tmp = file.string() + ".tmp" + std::to_string(::getpid());
  const auto fail = [&](const std::string& why) {
    return SnapshotError("cannot write snapshot " + file.string() + ": " + why);
  };
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw fail(std::strerror(errno));
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const std::string why = std::strerror(errno);
      ::close(fd);
      ::unlink(tmp.c_str());
      throw fail(why);
    }
    done += static_cast<std::size_t>(n);
  }
  // On disk before it takes the name: a crash now leaves the old file or the new, never half.
  if (::fsync(fd) != 0 || ::close(fd) != 0) {
    const std::string why = std::strerror(errno);
    ::unlink(tmp.c_str());
    throw fail(why);
  }
  if (std::rename(tmp.c_str(), file.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    ::unlink(tmp.c_str());
    throw fail(why);
  }
}

SavedState ReadSnapshotFile(const std::filesystem::path& file) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) {
    throw SnapshotError(file.string() + ": " + (std::filesystem::exists(file, ec) ? "not a regular file" : "no such file"));
  }
  const std::uintmax_t size = std::filesystem::file_size(file, ec);
  if (ec) throw SnapshotError(file.string() + ": " + ec.message());
  if (size > kMaxFileBytes) {
    throw SnapshotError(file.string() + ": " + std::to_string(size) + " bytes, too large to be an ÜberSim snapshot");
  }
  std::ifstream in(file, std::ios::binary);
  if (!in) throw SnapshotError(file.string() + ": cannot open: " + std::strerror(errno));
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw SnapshotError(file.string() + ": read error");
  return DecodeSnapshot(bytes, file.string());
}

std::uint64_t FileDigest(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return 0;
  std::uint64_t h = kFnv1aOffset;
  char buffer[65536];
  while (in.read(buffer, sizeof buffer) || in.gcount() > 0) Fnv1a(h, buffer, static_cast<std::size_t>(in.gcount()));
  return h;
}

}  // namespace ubersim::kernel
