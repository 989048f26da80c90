// SPDX-License-Identifier: Apache-2.0
// Micro-benchmarks of the hot paths: one physics step of each shipped world under random play,
// and the encoding of what leaves the simulator each frame (an SSL-Vision detection packet, a
// viewer state message). Run them all: `cmake --build build --target run-benchmarks`.
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>

#include <benchmark/benchmark.h>

#include "bench.hpp"
#include "ssl_vision_wrapper.pb.h"
#include "transport_common/wire_clock.hpp"
#include "ubersim/kernel/logging.hpp"
#include "vision_packets.hpp"
#include "viewer_protocol.hpp"

namespace ubersim::kernel {
namespace {

// A shipped world without transports, its robots driving at random.
struct PlayedWorld {
  std::ostringstream text;
  StreamLog log{text, LogLevel::kError};
  PluginRegistry registry{{UBERSIM_PLUGIN_BUILD_DIR}};
  std::unique_ptr<World> world;
  std::unique_ptr<bench::RandomPlay> play;

  // `robot`: a robot file under models/robots/ every robot of the world becomes; empty: as shipped.
  explicit PlayedWorld(const std::string& name, const PhysicsOverrides& physics = {},
                       const std::string& robot = "") {
    const ModelLoader loader(ModelLoader::DefaultSchemaDir(), [this](PluginKind k, const std::string& id) {
      return registry.Find(k, id).schema_json;
    });
    const std::optional<std::string> robot_file =
        robot.empty() ? std::nullopt : std::optional<std::string>(UBERSIM_SOURCE_DIR "/models/robots/" + robot);
    WorldModel model =
        bench::LoadTrialWorld(loader, UBERSIM_SOURCE_DIR "/models/worlds/" + name + ".yaml", physics, robot_file);
    model.transports.clear();
    world = std::make_unique<World>(model, registry, log, false);
    play = std::make_unique<bench::RandomPlay>(*world, 1);
    for (int i = 0; i < 200; ++i) Step();  // past the start, robots moving
  }
  void Step() {
    play->BeforeStep();
    world->Step();
  }
};

const char* const kWorlds[] = {"ssl-2003", "div-b", "div-a"};

// One step (events, plugins, collision, ODE, cameras) at the world file's own settings.
void BM_WorldStep(benchmark::State& state) {
  PlayedWorld w(kWorlds[state.range(0)]);
  for (auto _ : state) w.Step();
  state.SetLabel(kWorlds[state.range(0)]);
  state.counters["real_time_factor"] = benchmark::Counter(
      w.world->clock().step_seconds() * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_WorldStep)->DenseRange(0, 2)->Unit(benchmark::kMicrosecond);

// The same at a 5 ms step, the coarsest the league's simulators use.
void BM_WorldStep5ms(benchmark::State& state) {
  PhysicsOverrides coarse;
  coarse.step = 0.005;
  PlayedWorld w(kWorlds[state.range(0)], coarse);
  for (auto _ : state) w.Step();
  state.SetLabel(kWorlds[state.range(0)]);
  state.counters["real_time_factor"] = benchmark::Counter(
      w.world->clock().step_seconds() * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_WorldStep5ms)->DenseRange(0, 2)->Unit(benchmark::kMicrosecond);

// Div A at the validated fast settings (docs/performance.md): 5 ms, 10 solver iterations for
// the ball's islands and 2 for the rest, one contact per pair; with the wheel-body omni drive
// (0) and the single-body omni_force drive (1).
void BM_DivAFastSettings(benchmark::State& state) {
  PhysicsOverrides fast;
  fast.step = 0.005;
  fast.solver_iterations = 10;
  fast.solver_iterations_without_ball = 2;
  fast.max_contacts = 1;
  const bool force = state.range(0) == 1;
  PlayedWorld w("div-a", fast, force ? "ssl-omni-2026-force.yaml" : "");
  for (auto _ : state) w.Step();
  state.SetLabel(force ? "div-a omni_force" : "div-a omni");
  state.counters["real_time_factor"] = benchmark::Counter(
      w.world->clock().step_seconds() * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_DivAFastSettings)->DenseRange(0, 1)->Unit(benchmark::kMicrosecond);

// A camera frame of Div A (22 robots, the ball) as the frames the perception pipeline makes.
VisionFrame DivAFrame() {
  VisionFrame f;
  f.camera_id = 1;
  f.frame_number = 1234;
  f.t_capture_ns = 12'000'000'000;
  f.t_sent_ns = 12'035'000'000;
  f.balls.push_back(DetectedBall{0.5, -0.25, 0.0, 1.0});
  for (int i = 0; i < 22; ++i) {
    f.robots.push_back(DetectedRobot{RobotId{i < 11 ? Team::kBlue : Team::kYellow, i % 11},
                                     -5.0 + 0.45 * i, 0.1 * i, 0.05 * i, 1.0});
  }
  return f;
}

// Detection packet: SI to mm, the wrapper, serialised (what ssl_vision sends per frame).
void BM_VisionDetectionPacket(benchmark::State& state) {
  const VisionFrame frame = DivAFrame();
  transport::WireClock clock(transport::TimestampMode::kSim);
  ssl_vision::CameraIntrinsics intrinsics;
  ssl_vision::RobotHeights heights;
  std::string bytes;
  for (auto _ : state) {
    const SSL_WrapperPacket p = ssl_vision::DetectionPacket(frame, clock, intrinsics, nullptr, heights);
    p.SerializeToString(&bytes);
    benchmark::DoNotOptimize(bytes.data());
  }
  state.counters["bytes"] = static_cast<double>(bytes.size());
}
BENCHMARK(BM_VisionDetectionPacket);

// Viewer state message (JSON) of Div A with one camera frame.
void BM_ViewerStateMessage(benchmark::State& state) {
  PlayedWorld w("div-a");
  viewer::WorldSample sample;
  viewer::SampleSnapshot(w.world->GroundTruth(), sample);
  const std::vector<VisionFrame> frames{DivAFrame()};
  std::string json;
  for (auto _ : state) {
    json = viewer::EncodeState(sample, frames, viewer::ViewerStatus{});
    benchmark::DoNotOptimize(json.data());
  }
  state.counters["bytes"] = static_cast<double>(json.size());
}
BENCHMARK(BM_ViewerStateMessage);

}  // namespace
}  // namespace ubersim::kernel

BENCHMARK_MAIN();
