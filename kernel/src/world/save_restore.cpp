// SPDX-License-Identifier: Apache-2.0
// WorldImpl::Save and WorldImpl::Restore: the world's state to and from a SavedState (snapshot.hpp).
#include <cstring>
#include <ctime>
#include <set>

#include "ubersim/error.hpp"
#include "state/ode_state.hpp"
#include "ubersim/kernel/snapshot.hpp"
#include "world/world_impl.hpp"
#include "util/fnv1a.hpp"
#include "world/robot.hpp"

#ifndef UBERSIM_VERSION
#define UBERSIM_VERSION "unknown"
#endif

namespace ubersim::kernel {
namespace {

void Mix(std::uint64_t& h, double v) { Fnv1a(h, &v, sizeof v); }
void Mix(std::uint64_t& h, const std::string& s) {
  Fnv1a(h, s.data(), s.size());
  Fnv1a(h, "", 1);  // ends the string
}

// The files the world was built from, as the model names them (code-built models name none).
std::vector<ModelFileDigest> ModelFiles(const WorldModel& m) {
  std::vector<std::string> paths = {m.file, m.field->file, m.ball->file};
  std::vector<const RobotModel*> models;
  for (const RobotPlacement& p : m.robots) models.push_back(p.model.get());
  for (const auto& t : m.team_models) {
    if (t) models.push_back(t.get());
  }
  for (const RobotModel* model : models) {
    paths.push_back(model->file);
    if (!model->urdf_file.empty()) paths.push_back(model->urdf_file);
  }
  std::vector<ModelFileDigest> out;
  std::set<std::string> seen;
  for (const std::string& path : paths) {
    if (!seen.insert(path).second) continue;
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) continue;
    out.push_back(ModelFileDigest{path, FileDigest(path)});
  }
  return out;
}

std::string NowUtc() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return text;
}


}  // namespace

std::uint64_t WorldImpl::StructureDigest() const {
  std::uint64_t h = SceneDigest(*scene_);
  Mix(h, model_.name);
  const PhysicsModel& p = model_.physics;
  for (double v : {static_cast<double>(clock_.step_ns()), static_cast<double>(p.solver_iterations), p.erp, p.cfm,
                   p.gravity.x(), p.gravity.y(), p.gravity.z(), static_cast<double>(p.max_contacts),
                   p.contact_surface_layer, p.contact_max_correcting_velocity}) {
    Mix(h, v);
  }
  // Mixed in only when set, so a snapshot saved before the setting existed still restores.
  if (p.solver_iterations_without_ball) Mix(h, static_cast<double>(*p.solver_iterations_without_ball));
  if (p.speculative_robot_contacts) Mix(h, std::string("speculative_robot_contacts"));
  if (p.robot_contact_erp) Mix(h, *p.robot_contact_erp);
  Mix(h, p.broadphase);
  for (const auto& r : robots_) {
    Mix(h, ToString(r->id()));
    Mix(h, r->model().name);  // names the robot specs over the model, when there are
  }
  Mix(h, static_cast<double>(perception_.model().cameras.size()));
  Mix(h, perception_.model().frame_rate);
  return h;
}

SavedState WorldImpl::Save() const {
  SavedState s;
  s.world_name = model_.name;
  s.world_file = model_.file;
  s.field_file = model_.field->file;
  s.structure = StructureDigest();
  s.model_files = ModelFiles(model_);
  s.ubersim_version = UBERSIM_VERSION;
  s.created_utc = NowUtc();
  s.step = clock_.steps();
  s.time_ns = clock_.time_ns();
  s.step_ns = clock_.step_ns();
  s.ode_random_seed = ode_random_seed_;
  CaptureOdeState(*scene_, s);
  for (const auto& r : robots_) {
    SavedRobot saved;
    saved.id = r->id();
    saved.present = r->present();
    for (const RobotPlacement& p : roster_) {
      if (p.id != r->id()) continue;
      saved.model_file = p.model->file;
      saved.built_at = std::array<double, 3>{p.x, p.y, p.yaw};
    }
    for (PartState& p : r->SaveParts()) {
      saved.parts.push_back(SavedPart{p.kind, std::move(p.plugin), std::move(p.version), p.failed, std::move(p.state)});
    }
    s.robots.push_back(std::move(saved));
  }
  s.perception = perception_.SaveState();
  s.radio = radio_.SaveState();
  s.held_ball = held_ball_;
  s.ball_held_by = held_.holder();
  s.faults = faults_.faults();
  for (const auto& [key, spec] : specs_) s.robot_specs.emplace_back(RobotId{static_cast<Team>(key.first), key.second}, spec);
  return s;
}

void WorldImpl::Restore(const SavedState& s) {
  const std::string theirs = "world '" + s.world_name + "' (" + s.world_file + ")";
  const std::string ours = "world '" + model_.name + "' (" + model_.file + ")";
  if (s.world_name != model_.name) throw SnapshotError("the snapshot is of " + theirs + ", not of " + ours);
  if (s.step_ns != clock_.step_ns()) {
    throw SnapshotError("the snapshot's physics step is " + std::to_string(s.step_ns) + " ns, this world's " +
                        std::to_string(clock_.step_ns()) + " ns");
  }
  // The robots as they were: the world file's, those that came on, each from its model file.
  std::vector<RobotPlacement> roster;
  for (const SavedRobot& saved : s.robots) {
    RobotPlacement p;
    p.id = saved.id;
    p.present = saved.present;
    for (const RobotPlacement& known : model_.robots) {
      if (!p.model && known.id == saved.id && (saved.model_file.empty() || known.model->file == saved.model_file)) {
        p = known;
      }
    }
    for (const auto& team_model : model_.team_models) {
      if (!p.model && team_model && team_model->file == saved.model_file) p.model = team_model;
    }
    if (saved.built_at) {
      p.x = (*saved.built_at)[0];
      p.y = (*saved.built_at)[1];
      p.yaw = (*saved.built_at)[2];
    }
    if (!p.model) {
      throw SnapshotError("the snapshot's robot " + ToString(saved.id) + " was built from " +
                          (saved.model_file.empty() ? std::string("a model") : saved.model_file) + ", which " + ours +
                          " does not name (neither among its robots nor as a team's model)");
    }
    roster.push_back(std::move(p));
  }
  // Files edited since the snapshot: named whether the change is refused or only warned about.
  std::string changed;
  for (const ModelFileDigest& f : s.model_files) {
    if (std::filesystem::exists(f.path) && FileDigest(f.path) != f.digest) changed += (changed.empty() ? "" : ", ") + f.path;
  }
  // Built as the snapshot's world was (its field, its robots), then compared.
  const std::shared_ptr<const FieldModel> field_before = model_.field;
  if (!s.field_file.empty() && s.field_file != model_.field->file) {
    std::shared_ptr<const FieldModel> field;
    for (const auto& f : KnownFields()) {
      if (f->file == s.field_file) field = f;
    }
    if (!field) {
      throw SnapshotError("the snapshot's field is " + s.field_file + ", which " + ours + " does not name (fields:)");
    }
    UseField(field);
  }
  roster_ = std::move(roster);
  specs_.clear();
  spec_models_.clear();
  for (const auto& [id, spec] : s.robot_specs) specs_[{static_cast<int>(id.team), id.id}] = spec;
  Rebuild();
  if (s.structure != StructureDigest()) {
    UseField(field_before);
    roster_ = model_.robots;  // as freshly built
    specs_.clear();
    spec_models_.clear();
    Rebuild();
    throw SnapshotError("the snapshot's " + theirs + " has other bodies, geometries, masses or physics settings than " +
                        ours + (changed.empty() ? std::string() : "; changed since the snapshot: " + changed));
  }
  if (!changed.empty()) {
    log_.Warning("model files changed since the snapshot (" + changed +
                 "): the world goes on from the snapshot's state, but not as the original would have");
  }
  if (s.world_file != model_.file) log_.Info("the snapshot was taken of " + s.world_file);

  try {
    for (std::size_t i = 0; i < robots_.size(); ++i) {
      std::vector<PartState> parts;
      for (const SavedPart& p : s.robots[i].parts) parts.push_back(PartState{p.kind, p.plugin, p.version, p.failed, p.state});
      robots_[i]->RestoreParts(parts);
      robots_[i]->SetPresent(s.robots[i].present);
    }
    ApplyOdeState(*scene_, s);
    perception_.RestoreState(s.perception);
    radio_.RestoreState(s.radio);
    held_ball_ = s.held_ball;
    held_.Release();
    if (s.ball_held_by) {
      Robot* holder = FindRobot(*s.ball_held_by);
      if (!holder) throw std::invalid_argument("the robot holding the ball, " + ToString(*s.ball_held_by) + ", is not in this world");
      held_.Attach(world_.get(), holder->id(), holder->chassis().id(), ball_->id());
    }
  } catch (const std::exception& e) {
    UseField(field_before);
    roster_ = model_.robots;  // as freshly built, not half restored
    specs_.clear();
    spec_models_.clear();
    Rebuild();
    throw SnapshotError(std::string("cannot restore the snapshot into ") + ours + ": " + e.what());
  }
  clock_.Restore(s.step, s.time_ns);
  sim_time_ns_ = s.time_ns;
  ode_random_seed_ = static_cast<unsigned long>(s.ode_random_seed);
  faults_.Restore(s.faults);
  stopped_ = false;
  last_good_.Track(scene_->Root());
  log_.Info("restored the snapshot of step " + std::to_string(s.step) + " (" + std::to_string(1e-9 * s.time_ns) +
            " s), taken " + s.created_utc + " by ubersim " + s.ubersim_version);
  PublishGroundTruth();
  stopped_ = faults_.stop_requested();  // a transport failing on this first Publish
}

}  // namespace ubersim::kernel
