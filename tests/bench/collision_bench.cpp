// SPDX-License-Identifier: Apache-2.0
// Collision detection cost per step: the scene-graph collision manager against ODE's hash space
// and sweep-and-prune on the same scenes. Run: build/bin/collision_bench
#include <cmath>
#include <random>

#include <benchmark/benchmark.h>

#include "../common/random_scene.hpp"
#include "../common/ssl_scene.hpp"
#include "collision/collision.hpp"
#include "physics/ode_handles.hpp"

namespace ubersim::kernel {
namespace {

Broadphase FromIndex(int64_t i) {
  return i == 0 ? Broadphase::kSceneGraph : (i == 1 ? Broadphase::kHash : (i == 2 ? Broadphase::kSweepAndPrune : Broadphase::kField));
}

// One collision pass (broadphase + narrow phase + contact joints) on an SSL scene.
void BM_SslScene(benchmark::State& state) {
  OdeLibrary ode;
  OdeWorld world(dWorldCreate());
  SceneGraph graph(world.get());
  std::mt19937_64 rng(42);
  testing::BuildSslScene(graph, static_cast<int>(state.range(1)), rng);
  CollisionManager cm(graph, FromIndex(state.range(0)), 4);
  std::size_t contacts = 0;
  for (auto _ : state) {
    cm.Collide();
    contacts = cm.stats().contacts;
    cm.ClearContacts();
  }
  state.SetLabel(ToString(FromIndex(state.range(0))));
  state.counters["contacts"] = static_cast<double>(contacts);
  state.counters["narrow_tests"] = static_cast<double>(cm.stats().narrow_tests);
}
BENCHMARK(BM_SslScene)
    ->ArgNames({"broadphase", "robots_per_team"})
    ->ArgsProduct({{0, 1, 2, 3}, {5, 6, 11}})
    ->Unit(benchmark::kMicrosecond);

// Candidate pairs only on the random nested scenes of the exactness test.
void BM_RandomScene(benchmark::State& state) {
  OdeLibrary ode;
  OdeWorld world(dWorldCreate());
  SceneGraph graph(world.get());
  std::mt19937_64 rng(7);
  testing::RandomSceneSpec spec;
  spec.top_nodes = static_cast<int>(state.range(1));
  spec.extent = std::cbrt(spec.top_nodes / 6.0);  // keep density constant as the scene grows
  testing::BuildRandomScene(graph, rng, spec);
  CollisionManager cm(graph, FromIndex(state.range(0)), 4);
  std::size_t pairs = 0;
  for (auto _ : state) {
    pairs = 0;
    cm.ForEachCandidatePair([&](GeomImpl&, GeomImpl&) { ++pairs; });
    benchmark::DoNotOptimize(pairs);
  }
  state.SetLabel(ToString(FromIndex(state.range(0))));
  state.counters["candidates"] = static_cast<double>(pairs);
}
BENCHMARK(BM_RandomScene)
    ->ArgNames({"broadphase", "top_nodes"})
    ->ArgsProduct({{0, 1, 2, 3}, {6, 24}})
    ->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace ubersim::kernel

BENCHMARK_MAIN();
