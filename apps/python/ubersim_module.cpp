// SPDX-License-Identifier: Apache-2.0
// _ubersim: one world of the kernel's public API for Python (ubersim/__init__.py wraps it). Loads
// a world as `ubersim run` does (shipped name or file, its plugins), steps it, reads its state into
// numpy arrays (SI units), takes robot commands and teleports, saves and restores. Errors become
// Python exceptions carrying the CLI's text (file:line:column: key) and its exit code.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cmath>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "module_common.hpp"
#include "shared/random_play.hpp"
#include "shared/world_loading.hpp"
#include "ubersim/kernel/logging.hpp"
#include "ubersim/kernel/model.hpp"
#include "ubersim/kernel/plugin_registry.hpp"
#include "ubersim/kernel/snapshot.hpp"
#include "ubersim/kernel/world.hpp"

namespace py = pybind11;

namespace ubersim::python {
namespace {

using kernel::World;

Team TeamOf(const std::string& name) {
  if (name == "blue") return Team::kBlue;
  if (name == "yellow") return Team::kYellow;
  throw py::value_error("team must be 'blue' or 'yellow', not '" + name + "'");
}

// One world with what it was loaded with (the registry outlives the world: its plugins' code).
class PyWorld {
 public:
  explicit PyWorld(const WorldSettings& settings)
      : loaded_(LoadForPython(settings)), log_(log_text_, LogLevel::kWarning) {
    OdeSection ode;
    world_ = std::make_unique<World>(loaded_.model, *loaded_.loading.registry, log_, false);
  }

  void Step(int steps) {
    if (steps < 0) throw py::value_error("steps must be >= 0");
    OdeSection ode;
    for (int i = 0; i < steps; ++i) {
      if (random_play_) random_play_->BeforeStep();
      world_->Step();
    }
  }
  // The bench's random play drives every robot from now on (None: stops it).
  void RandomPlay(std::optional<std::uint64_t> seed) {
    if (!seed) {
      random_play_.reset();
      return;
    }
    OdeSection ode;
    random_play_ = std::make_unique<apps::RandomPlay>(*world_, *seed);
  }
  py::dict Field() const { return FieldDict(world_->model().field->geometry); }
  double Time() const { return world_->clock().seconds(); }
  std::int64_t Steps() const { return world_->clock().steps(); }
  double StepSeconds() const { return static_cast<double>(world_->clock().step_ns()) * 1e-9; }
  std::uint64_t Hash() const { return world_->StateHash(); }
  std::string Name() const { return loaded_.model.name; }
  void Reset(std::optional<std::uint64_t> seed) {
    OdeSection ode;
    random_play_.reset();
    if (seed) {
      world_->Reset(*seed);
    } else {
      world_->Reset();
    }
  }

  // The state as numpy arrays: robots in the world's order (blue first, then yellow, by id).
  py::dict State() const {
    const WorldSnapshot s = [this] {
      OdeSection ode;
      return world_->GroundTruth();
    }();
    const auto n = static_cast<py::ssize_t>(s.robots.size());
    py::array_t<std::int32_t> ids({n, py::ssize_t{2}});
    py::array_t<double> pose({n, py::ssize_t{3}}), vel({n, py::ssize_t{3}});
    py::array_t<bool> present(n);
    auto id = ids.mutable_unchecked<2>();
    auto p = pose.mutable_unchecked<2>();
    auto v = vel.mutable_unchecked<2>();
    auto on = present.mutable_unchecked<1>();
    for (py::ssize_t i = 0; i < n; ++i) {
      const RobotState& r = s.robots[static_cast<std::size_t>(i)];
      id(i, 0) = r.id.team == Team::kBlue ? 0 : 1;
      id(i, 1) = r.id.id;
      p(i, 0) = r.pose.position.x();
      p(i, 1) = r.pose.position.y();
      p(i, 2) = r.pose.Yaw();
      v(i, 0) = r.twist.linear.x();
      v(i, 1) = r.twist.linear.y();
      v(i, 2) = r.twist.angular.z();
      on(i) = r.present;
    }
    py::array_t<double> ball_pos(3), ball_vel(3);
    for (int k = 0; k < 3; ++k) {
      ball_pos.mutable_at(k) = s.ball.pose.position[k];
      ball_vel.mutable_at(k) = s.ball.twist.linear[k];
    }
    py::dict out;
    out["time"] = static_cast<double>(s.sim_time_ns) * 1e-9;
    out["robot_ids"] = ids;
    out["robot_pose"] = pose;
    out["robot_velocity"] = vel;
    out["robot_present"] = present;
    out["ball_position"] = ball_pos;
    out["ball_velocity"] = ball_vel;
    return out;
  }

  void Command(const std::string& team, int id, double vx, double vy, double angular, bool global, double kick_speed,
               double chip_angle, std::optional<double> dribbler) {
    CommandEvent e;
    e.robot = {TeamOf(team), id};
    if (global) {
      e.move = GlobalVelocityCommand{vx, vy, angular};
    } else {
      e.move = LocalVelocityCommand{vx, vy, angular};
    }
    if (kick_speed > 0) e.kick = KickCommand{kick_speed, chip_angle};
    e.dribbler_speed = dribbler;
    world_->events().Post(std::move(e));  // the queue is thread-safe: no ODE here
  }

  void PlaceBall(double x, double y, double z, double vx, double vy, double vz) {
    PositionEvent e;
    e.target = Target::Ball();
    e.position = Vec3(x, y, z);
    e.velocity = Vec3(vx, vy, vz);
    e.angular_velocity = Vec3::Zero();
    world_->events().Post(std::move(e));
    OdeSection ode;
    world_->ProcessEvents();
  }

  void PlaceRobot(const std::string& team, int id, double x, double y, double yaw, bool present) {
    PositionEvent e;
    e.target = Target::Robot({TeamOf(team), id});
    e.position = Vec3(x, y, 0);
    e.yaw = yaw;
    e.velocity = Vec3::Zero();
    e.angular_velocity = Vec3::Zero();
    e.present = present;
    world_->events().Post(std::move(e));
    OdeSection ode;
    world_->ProcessEvents();
  }

  py::bytes Save() const { return SaveWorld(*world_); }
  void Restore(const std::string& bytes) {
    random_play_.reset();  // its schedule is of the state left behind
    RestoreWorld(*world_, bytes);
  }
  std::string LogText() const { return log_text_.str(); }

 private:
  apps::LoadedWorld loaded_;
  std::ostringstream log_text_;
  kernel::StreamLog log_;
  std::unique_ptr<World> world_;
  std::unique_ptr<apps::RandomPlay> random_play_;
};

}  // namespace

void BindVectorWorlds(py::module_& m);  // vector_bindings.cpp

}  // namespace ubersim::python

PYBIND11_MODULE(_ubersim, m) {
  using ubersim::python::PyWorld;

  m.doc() = "ÜberSim's kernel for Python: one world, stepped, read and commanded (docs/python.md).";
  // The CLI's errors, with its exit codes (docs/cli.md): ModelError 3, PluginError 4, SnapshotError 1.
  static py::exception<std::runtime_error> model_error(m, "ModelError", PyExc_ValueError);
  static py::exception<std::runtime_error> plugin_error(m, "PluginError", PyExc_RuntimeError);
  static py::exception<std::runtime_error> snapshot_error(m, "SnapshotError", PyExc_ValueError);
  model_error.attr("exit_code") = 3;
  plugin_error.attr("exit_code") = 4;
  snapshot_error.attr("exit_code") = 1;
  py::register_exception_translator([](std::exception_ptr error) {
    try {
      if (error) std::rethrow_exception(error);
    } catch (const ubersim::kernel::PluginLookupError& e) {  // a model names a plugin not found: a plugin error, as in the CLI
      PyErr_SetString(plugin_error.ptr(), e.what());
    } catch (const ubersim::kernel::ModelError& e) {
      PyErr_SetString(model_error.ptr(), e.what());
    } catch (const ubersim::ParamError& e) {
      PyErr_SetString(model_error.ptr(), e.what());
    } catch (const ubersim::kernel::PluginLoadError& e) {
      PyErr_SetString(plugin_error.ptr(), e.what());
    } catch (const ubersim::PluginError& e) {
      PyErr_SetString(plugin_error.ptr(), e.what());
    } catch (const ubersim::kernel::SnapshotError& e) {
      PyErr_SetString(snapshot_error.ptr(), e.what());
    }
  });
  py::class_<PyWorld>(m, "World", "One simulated SSL field (a world file or a shipped world's name).")
      .def(py::init([](const std::string& world, const std::vector<std::string>& plugin_paths,
                       std::optional<std::uint64_t> seed, std::optional<std::string> profile,
                       std::optional<py::dict> physics, std::optional<std::string> robot) {
             return std::make_unique<PyWorld>(ubersim::python::WorldSettings{
                 world, plugin_paths, seed, profile, physics.value_or(py::dict()), robot});
           }),
           py::arg("world"), py::arg("plugin_paths") = std::vector<std::string>{}, py::arg("seed") = py::none(),
           py::arg("profile") = py::none(), py::arg("physics") = py::none(), py::arg("robot") = py::none(),
           "Loads WORLD (a file, or a shipped world's name such as 'div-b') with its plugins, without sockets; "
           "`physics` sets physics keys over the profile, `robot` a robot model file for every robot.")
      .def("step", &PyWorld::Step, py::arg("steps") = 1, "Advances the world by `steps` physics steps.")
      .def("random_play", &PyWorld::RandomPlay, py::arg("seed"),
           "The bench's seeded random play drives every robot from now on (None stops it).")
      .def("state", &PyWorld::State, "The state now as numpy arrays (SI units, the field frame).")
      .def("command", &PyWorld::Command, py::arg("team"), py::arg("id"), py::arg("vx") = 0.0, py::arg("vy") = 0.0,
           py::arg("angular") = 0.0, py::arg("global_frame") = false, py::arg("kick_speed") = 0.0,
           py::arg("chip_angle") = 0.0, py::arg("dribbler") = py::none(),
           "Sends a robot command (velocity in the robot's frame, or the field's with global_frame).")
      .def("place_ball", &PyWorld::PlaceBall, py::arg("x"), py::arg("y"), py::arg("z") = 0.0215, py::arg("vx") = 0.0,
           py::arg("vy") = 0.0, py::arg("vz") = 0.0, "Puts the ball at (x, y, z) m with velocity (vx, vy, vz) m/s.")
      .def("place_robot", &PyWorld::PlaceRobot, py::arg("team"), py::arg("id"), py::arg("x"), py::arg("y"),
           py::arg("yaw") = 0.0, py::arg("present") = true, "Puts a robot at (x, y) m heading yaw rad, or off the field.")
      .def("save", &PyWorld::Save, "The world's full state as bytes (a snapshot).")
      .def("restore", &PyWorld::Restore, py::arg("snapshot"), "Puts a saved state back: stepping on is bit-identical.")
      .def("reset", &PyWorld::Reset, py::arg("seed") = py::none(),
           "Puts everything back where the world file has it (with another seed when given).")
      .def_property_readonly("field", &PyWorld::Field, "The field's geometry: sizes (m) and markings.")
      .def_property_readonly("time", &PyWorld::Time, "Simulated time, s.")
      .def_property_readonly("steps", &PyWorld::Steps, "Physics steps since the start.")
      .def_property_readonly("step_seconds", &PyWorld::StepSeconds, "The physics step, s.")
      .def_property_readonly("state_hash", &PyWorld::Hash, "A hash of every body's state, bit for bit.")
      .def_property_readonly("name", &PyWorld::Name, "The world's name.")
      .def_property_readonly("log", &PyWorld::LogText, "What the world logged (warnings and errors).");
  ubersim::python::BindVectorWorlds(m);
}
