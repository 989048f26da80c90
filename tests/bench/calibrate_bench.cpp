// SPDX-License-Identifier: Apache-2.0
// `ubersim calibrate` on a long log: reading and fitting a drill of UBERSIM_CALIBRATE_BENCH_SECONDS
// simulated seconds (default 3600: a one-hour session, 270 000 camera frames of the shipped Div B
// world's one 75 Hz camera). The drill is recorded once into the build tree and reused. Run by
// hand: build/tests/bench/calibrate_bench; ctest runs a 20 s smoke test.
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string>

#include "calibration.hpp"
#include "drill.hpp"
#include "log_session.hpp"
#include "shared/world_loading.hpp"
#include "ubersim/kernel/logging.hpp"
#include "ubersim/kernel/world.hpp"

namespace {

namespace fs = std::filesystem;
using namespace ubersim;

fs::path DivB() { return fs::path(UBERSIM_SOURCE_DIR) / "models/worlds/div-b.yaml"; }

double BenchSeconds() {
  const char* s = std::getenv("UBERSIM_CALIBRATE_BENCH_SECONDS");
  return s ? std::atof(s) : 3600.0;
}

// The drill log of the shipped Div B world, recorded when not yet there.
const std::string& DrillLog() {
  static const std::string path = [] {
    const double seconds = BenchSeconds();
    const fs::path file = fs::path(UBERSIM_BINARY_DIR) / ("calibrate_bench_div-b_" + std::to_string(static_cast<int>(seconds)) + "s.log");
    if (!fs::exists(file)) {
      auto loaded = apps::LoadWorldWithPlugins(DivB(), {UBERSIM_PLUGIN_BUILD_DIR});
      loaded.model.transports.clear();
      kernel::StreamLog log(std::cerr, LogLevel::kWarning);
      kernel::World world(loaded.model, *loaded.loading.registry, log, false);
      calibrate::DrillOptions options;
      options.duration = seconds;
      const fs::path partial = file.string() + ".partial";
      calibrate::RunDrill(world, partial.string(), options, log);
      fs::rename(partial, file);
    }
    return file.string();
  }();
  return path;
}

void BM_ReadLog(benchmark::State& state) {
  const std::string& log = DrillLog();
  std::size_t frames = 0;
  for (auto _ : state) {
    const calibrate::LogSession s = calibrate::ReadLogSession({log});
    frames = s.frames.size();
    benchmark::DoNotOptimize(frames);
  }
  state.counters["camera_frames"] = static_cast<double>(frames);
  state.counters["frames_per_s"] = benchmark::Counter(static_cast<double>(frames) * state.iterations(), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_ReadLog)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

// The whole command without --check: read, track, fit (ball and cameras beside the robots), write.
void BM_Calibrate(benchmark::State& state) {
  const std::string& log = DrillLog();
  calibrate::CalibrateOptions options;
  options.logs = {log};
  options.out_dir = fs::path(UBERSIM_BINARY_DIR) / "calibrate_bench_out";
  options.base_world = DivB();
  double reading = 0, fitting = 0, ball = 0, robots = 0, cameras = 0;
  bool fitted = false;
  for (auto _ : state) {
    const auto outcome = calibrate::Calibrate(options, [](const std::string&) {});
    reading = outcome.seconds_reading;
    fitting = outcome.seconds_fitting;
    ball = outcome.seconds_ball;
    robots = outcome.seconds_robots;
    cameras = outcome.seconds_cameras;
    fitted = outcome.fits.ball.enough_data && outcome.fits.cameras.enough_data;
  }
  state.counters["reading_s"] = reading;
  state.counters["fitting_s"] = fitting;
  state.counters["ball_s"] = ball;
  state.counters["robots_s"] = robots;
  state.counters["cameras_s"] = cameras;
  if (!fitted) state.SkipWithError("the drill log did not give a ball and camera fit");
}
BENCHMARK(BM_Calibrate)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
