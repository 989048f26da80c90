// SPDX-License-Identifier: Apache-2.0
// _ubersim.VectorWorlds: K worlds stepped by one call, actions and observations in numpy arrays
// the caller owns (ubersim/env.py builds VectorEnv, Env and ParallelEnv on it).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <string>

#include "module_common.hpp"
#include "vector_worlds.hpp"

namespace ubersim::python {

namespace {

using FloatArray = py::array_t<float, py::array::c_style>;
using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

// Checks that `a` is a C-contiguous float32 array of exactly this shape (no copy: it is written
// to or read from in place).
void ExpectShape(const py::array& a, std::initializer_list<py::ssize_t> shape, const char* what) {
  bool ok = a.ndim() == static_cast<py::ssize_t>(shape.size()) && a.dtype().is(py::dtype::of<float>()) &&
            (a.flags() & py::array::c_style) != 0;
  std::string expected = "(";
  int i = 0;
  for (py::ssize_t n : shape) {
    if (ok && a.shape(i) != n) ok = false;
    expected += (i ? ", " : "") + std::to_string(n);
    ++i;
  }
  expected += ")";
  if (!ok) {
    std::string got = "(";
    for (py::ssize_t d = 0; d < a.ndim(); ++d) got += (d ? ", " : "") + std::to_string(a.shape(d));
    got += ")";
    throw py::value_error(std::string(what) + " must be a C-contiguous float32 array of shape " + expected +
                          ", not " + std::string(py::str(a.dtype())) + " " + got);
  }
}

class PyVectorWorlds {
 public:
  PyVectorWorlds(const WorldSettings& settings, const VectorWorldsOptions& options) {
    apps::LoadedWorld loaded = LoadForPython(settings);
    OdeSection ode;
    core_ = std::make_unique<VectorWorlds>(std::move(loaded), options);
  }

  void Step(const py::array& actions, const py::array& obs) {
    ExpectShape(actions, {core_->count(), core_->controlled(), action::kCount}, "actions");
    ExpectShape(obs, {core_->count(), core_->robots(), core_->features()}, "obs");
    if (!obs.writeable()) throw py::value_error("obs must be writeable");
    const auto* a = static_cast<const float*>(actions.data());
    auto* o = static_cast<float*>(const_cast<void*>(obs.data()));
    OdeSection ode;
    core_->Step(a, o);
  }

  void Observe(const py::array& obs) {
    ExpectShape(obs, {core_->count(), core_->robots(), core_->features()}, "obs");
    auto* o = static_cast<float*>(const_cast<void*>(obs.data()));
    OdeSection ode;
    core_->Observe(o);
  }

  // Starts the next episode of each world in `indices` with its seed; a task's start (robot
  // poses n × robots × 3, presence n × robots, ball n × 6) or the world file's when None.
  void Reset(const std::vector<int>& indices, const std::vector<std::uint64_t>& seeds, const py::array& obs,
             std::optional<DoubleArray> robot_pose, std::optional<py::array_t<bool>> present,
             std::optional<DoubleArray> ball) {
    ExpectShape(obs, {core_->count(), core_->robots(), core_->features()}, "obs");
    const auto n = static_cast<py::ssize_t>(indices.size());
    if (seeds.size() != indices.size()) throw py::value_error("one seed per world reset");
    const py::ssize_t robots = core_->robots();
    if (robot_pose && (robot_pose->ndim() != 3 || robot_pose->shape(0) != n || robot_pose->shape(1) != robots ||
                       robot_pose->shape(2) != 3)) {
      throw py::value_error("robot_pose must be of shape (" + std::to_string(n) + ", " + std::to_string(robots) +
                            ", 3): x, y, yaw of every robot of every world reset");
    }
    if (robot_pose && (!present || present->ndim() != 2 || present->shape(0) != n || present->shape(1) != robots)) {
      throw py::value_error("robot_present must be of shape (" + std::to_string(n) + ", " + std::to_string(robots) +
                            ") beside robot_pose");
    }
    if (ball && (ball->ndim() != 2 || ball->shape(0) != n || ball->shape(1) != 6)) {
      throw py::value_error("ball must be of shape (" + std::to_string(n) + ", 6): x, y, z, vx, vy, vz");
    }
    std::vector<EpisodeStart> starts(indices.size());
    for (py::ssize_t j = 0; j < n; ++j) {
      const int k = indices[static_cast<std::size_t>(j)];
      if (k < 0 || k >= core_->count()) throw py::index_error("no world " + std::to_string(k));
      EpisodeStart& s = starts[static_cast<std::size_t>(j)];
      if (robot_pose) {
        const auto pose = robot_pose->unchecked<3>();
        const auto on = present->unchecked<2>();
        for (py::ssize_t i = 0; i < robots; ++i) {
          for (int c = 0; c < 3; ++c) s.robot_pose.push_back(pose(j, i, c));
          s.present.push_back(on(j, i) ? 1 : 0);
        }
      }
      if (ball) {
        const auto b = ball->unchecked<2>();
        for (int c = 0; c < 6; ++c) s.ball[static_cast<std::size_t>(c)] = b(j, c);
        s.has_ball = true;
      }
    }
    auto* o = static_cast<float*>(const_cast<void*>(obs.data()));
    const std::size_t stride = static_cast<std::size_t>(core_->robots() * core_->features());
    OdeSection ode;
    for (std::size_t j = 0; j < indices.size(); ++j) {
      const int k = indices[j];
      core_->Reset(k, seeds[j], starts[j], o + static_cast<std::size_t>(k) * stride);
    }
  }

  // Each robot row's id: team (0 blue, 1 yellow) and id.
  py::array_t<std::int32_t> Slots() const {
    py::array_t<std::int32_t> out({static_cast<py::ssize_t>(core_->robots()), py::ssize_t{2}});
    auto o = out.mutable_unchecked<2>();
    for (int i = 0; i < core_->robots(); ++i) {
      o(i, 0) = static_cast<int>(core_->slots()[static_cast<std::size_t>(i)].team);
      o(i, 1) = core_->slots()[static_cast<std::size_t>(i)].id;
    }
    return out;
  }
  py::array_t<std::int32_t> Controlled() const {
    py::array_t<std::int32_t> out(static_cast<py::ssize_t>(core_->controlled()));
    for (int c = 0; c < core_->controlled(); ++c) out.mutable_at(c) = core_->controlled_slots()[static_cast<std::size_t>(c)];
    return out;
  }
  // Low (row 0) and high (row 1) of every action component of every robot row.
  py::array_t<float> ActionBounds() const {
    py::array_t<float> out({py::ssize_t{2}, static_cast<py::ssize_t>(core_->robots()), py::ssize_t{action::kCount}});
    auto o = out.mutable_unchecked<3>();
    for (int i = 0; i < core_->robots(); ++i) {
      const auto bounds = core_->ActionBounds(i);
      for (int side = 0; side < 2; ++side) {
        for (int c = 0; c < action::kCount; ++c) o(side, i, c) = static_cast<float>(bounds[side][c]);
      }
    }
    return out;
  }

  int count() const { return core_->count(); }
  int robots() const { return core_->robots(); }
  int features() const { return core_->features(); }
  int controlled() const { return core_->controlled(); }
  double step_seconds() const { return core_->step_seconds(); }
  std::int64_t physics_steps() const { return core_->physics_steps(); }
  std::string profile() const { return core_->model().physics.profile; }
  std::string name() const { return core_->model().name; }
  py::dict field() const { return FieldDict(core_->model().field->geometry); }
  std::uint64_t StateHash(int k) {
    Check(k);
    OdeSection ode;
    return core_->world(k).StateHash();
  }
  double Time(int k) {
    Check(k);
    return core_->world(k).clock().seconds();
  }
  py::bytes Save(int k) {
    Check(k);
    return SaveWorld(core_->world(k));
  }
  void Restore(int k, const std::string& bytes) {
    Check(k);
    RestoreWorld(core_->world(k), bytes);
    OdeSection ode;
    core_->RefreshPresence(k);
  }

 private:
  void Check(int k) const {
    if (k < 0 || k >= core_->count()) throw py::index_error("no world " + std::to_string(k));
  }
  std::unique_ptr<VectorWorlds> core_;
};

}  // namespace

void BindVectorWorlds(py::module_& m) {
  m.attr("FEATURES_BASE") = feature::kBase;
  m.attr("FEATURES_WITH_CAMERAS") = feature::kWithCameras;
  m.attr("ACTION_COMPONENTS") = action::kCount;
  py::class_<PyVectorWorlds>(m, "VectorWorlds",
                             "K copies of one world stepped by one call (the core of ubersim.VectorEnv).")
      .def(py::init([](const std::string& world, int count, int frame_skip, const std::string& blue,
                       const std::string& yellow, bool camera_features,
                       const std::vector<std::string>& plugin_paths, std::optional<std::uint64_t> seed,
                       std::optional<std::string> profile, std::optional<py::dict> physics,
                       std::optional<std::string> robot) {
             VectorWorldsOptions options;
             options.count = count;
             options.frame_skip = frame_skip;
             try {
               options.drivers = {DriverNamed(blue), DriverNamed(yellow)};
             } catch (const std::invalid_argument& e) {
               throw py::value_error(e.what());
             }
             options.camera_features = camera_features;
             if (count < 1) throw py::value_error("count must be at least 1");
             if (frame_skip < 1) throw py::value_error("frame_skip must be at least 1");
             return std::make_unique<PyVectorWorlds>(
                 WorldSettings{world, plugin_paths, seed, profile, physics.value_or(py::dict()), robot}, options);
           }),
           py::arg("world"), py::arg("count"), py::arg("frame_skip") = 1, py::arg("blue") = "agent",
           py::arg("yellow") = "idle", py::arg("camera_features") = false,
           py::arg("plugin_paths") = std::vector<std::string>{}, py::arg("seed") = py::none(),
           py::arg("profile") = py::none(), py::arg("physics") = py::none(), py::arg("robot") = py::none())
      .def("step", &PyVectorWorlds::Step, py::arg("actions"), py::arg("obs"),
           "Sends `actions` (K × controlled × 6 float32), steps every world frame_skip times, writes `obs`.")
      .def("observe", &PyVectorWorlds::Observe, py::arg("obs"), "Writes every world's observation into `obs`.")
      .def("reset", &PyVectorWorlds::Reset, py::arg("indices"), py::arg("seeds"), py::arg("obs"),
           py::arg("robot_pose") = py::none(), py::arg("robot_present") = py::none(), py::arg("ball") = py::none(),
           "Starts the next episode of the worlds `indices` with `seeds`, at a task's start or the file's.")
      .def_property_readonly("slots", &PyVectorWorlds::Slots, "Each robot row's (team, id); team 0 blue, 1 yellow.")
      .def_property_readonly("controlled", &PyVectorWorlds::Controlled, "The robot rows the actions move.")
      .def_property_readonly("action_bounds", &PyVectorWorlds::ActionBounds,
                             "Low and high of each action component, 2 × robots × 6.")
      .def_property_readonly("count", &PyVectorWorlds::count, "K, the number of worlds.")
      .def_property_readonly("robots", &PyVectorWorlds::robots, "Robot rows per world.")
      .def_property_readonly("features", &PyVectorWorlds::features, "Features per robot row.")
      .def_property_readonly("controlled_count", &PyVectorWorlds::controlled, "Robots the actions move per world.")
      .def_property_readonly("step_seconds", &PyVectorWorlds::step_seconds, "The physics step, s.")
      .def_property_readonly("physics_steps", &PyVectorWorlds::physics_steps, "Physics steps of all worlds so far.")
      .def_property_readonly("profile", &PyVectorWorlds::profile, "The physics profile in force.")
      .def_property_readonly("name", &PyVectorWorlds::name, "The world's name.")
      .def_property_readonly("field", &PyVectorWorlds::field, "The field's geometry: sizes (m) and markings.")
      .def("state_hash", &PyVectorWorlds::StateHash, py::arg("index"), "World `index`'s state hash.")
      .def("time", &PyVectorWorlds::Time, py::arg("index"), "World `index`'s simulated time, s.")
      .def("save", &PyVectorWorlds::Save, py::arg("index"), "World `index`'s full state as bytes.")
      .def("restore", &PyVectorWorlds::Restore, py::arg("index"), py::arg("snapshot"),
           "Puts a saved state back into world `index`.");
}

}  // namespace ubersim::python
