/// BM_Step/<strips>: one substep of the full core (gravity, head motion, wind, springs, the 5 default
/// bodies) on strips of 2 x 5 control points, after 1 s of the motion (kWarmupSubsteps); items =
/// control-point updates.
#include <benchmark/benchmark.h>

#include <cmath>
#include <map>
#include <memory>
#include <tuple>

#include "BenchMotion.hpp"
#include "hair_sim/core/Simulator.hpp"
#include "hair_sim/core/geometry/HairMeshBuilder.hpp"
#include "hair_sim/core/model/HairstyleGenerator.hpp"
#include "hair_sim/core/model/SimConfig.hpp"
#include "hair_sim/tools/OfflineRunner.hpp"

namespace {

using namespace hair_sim;
using hair_sim::bench::benchHairstyle;

/// Simulator set-up (chains, rest compensation, spring pairs through the grid); items = strips.
void BM_Setup(benchmark::State& state) {
  const SimConfig config = loadSimConfig(std::string(HAIR_SIM_REPO_ROOT) + "/config/hair_sim.yaml");
  const Hairstyle style = benchHairstyle(config, static_cast<int>(state.range(0)));
  for (auto _ : state) {
    Simulator sim(style, config.physics, config.bodies);
    benchmark::DoNotOptimize(sim.springs().size());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<long>(style.strips.size()));
}
BENCHMARK(BM_Setup)->Arg(100)->Arg(1000)->Arg(10000)->Unit(benchmark::kMillisecond);

/// Substeps of BM_Step's motion before any timing: 1 s, the hair fallen from its styled shape and lying on
/// the bodies (as BM_MeshBuild). From rest the first substeps are cheaper (at 10,000 strips 98 ns per update
/// over the first 40 against 145 after 240, with 0.11 of the strips in the exact step against 0.27), and
/// Google Benchmark times 0.5 s: 6,000 substeps at 100 strips but only about 40 at 10,000. Every size is
/// timed in the same phase of the motion.
constexpr long kWarmupSubsteps = 240;

/// BM_Step's simulator of `strips` strips, warmed up by kWarmupSubsteps of its motion once per (strips, path,
/// threads) and kept for the benchmark's later runs (Google Benchmark calls a benchmark several times per
/// repetition), which go on with the motion.
bench::MotionRun& warmSimulator(int strips, Simulator::StepPath path, int threads) {
  static std::map<std::tuple<int, int, int>, std::unique_ptr<bench::MotionRun>> cache;
  std::unique_ptr<bench::MotionRun>& w = cache[std::make_tuple(strips, static_cast<int>(path), threads)];
  if (!w) {
    const SimConfig config = loadSimConfig(std::string(HAIR_SIM_REPO_ROOT) + "/config/hair_sim.yaml");
    w = std::make_unique<bench::MotionRun>(config, strips, path, threads, kWarmupSubsteps);
  }
  return *w;
}

void runStep(benchmark::State& state, Simulator::StepPath path, int threads = 1) {
  bench::MotionRun& w = warmSimulator(static_cast<int>(state.range(0)), path, threads);
  Simulator& sim = w.sim;
  long n = 0;
  double exact = 0.0;
  for (auto _ : state) {
    ++n;
    w.step();
    exact += sim.exactStripCount();
  }
  state.SetItemsProcessed(state.iterations() * sim.controlPointCount());
  state.counters["control_points"] = sim.controlPointCount();
  state.counters["strips"] = static_cast<double>(sim.hairstyle().strips.size());
  // Share of the strips that took the exact per-strip step (Simulator::StepPath).
  state.counters["exact_share"] =
      exact / (static_cast<double>(n) * static_cast<double>(sim.hairstyle().strips.size()));
}
/// The default path (Simulator::StepPath::Lanes).
void BM_Step(benchmark::State& state) { runStep(state, Simulator::StepPath::Lanes); }
BENCHMARK(BM_Step)->Arg(100)->Arg(1000)->Arg(10000)->Unit(benchmark::kMillisecond);
/// Every strip through the exact per-strip step (the path before the lanes), for the ratio in one run.
void BM_StepExact(benchmark::State& state) { runStep(state, Simulator::StepPath::Exact); }
BENCHMARK(BM_StepExact)->Arg(100)->Arg(1000)->Arg(10000)->Unit(benchmark::kMillisecond);
/// The lanes without AVX2 (what a CPU without it runs).
void BM_StepBaseline(benchmark::State& state) { runStep(state, Simulator::StepPath::LanesBaseline); }
BENCHMARK(BM_StepBaseline)->Arg(1000)->Unit(benchmark::kMillisecond);
/// The default path with a helper thread (Simulator::setThreads(2)): items per second of wall time.
void BM_Step2Threads(benchmark::State& state) { runStep(state, Simulator::StepPath::Lanes, 2); }
BENCHMARK(BM_Step2Threads)->Arg(100)->Arg(1000)->Arg(10000)->Unit(benchmark::kMillisecond)->UseRealTime();

/// BM_MeshBuild/<strips>/<threads>: what hair_sim_node does for hair_markers each frame before writing the
/// message, on the default config's bodies and a generated hairstyle after 1 s of BM_Step's motion (hair
/// lying on the bodies):
/// HairMeshBuilder::build at the default level of detail (tessellation, root edge onto the scalp, vertices
/// out of the 5 bodies, the look); items = vertices; threads: HairMeshBuilder::setThreads (wall time).
void BM_MeshBuild(benchmark::State& state) {
  const SimConfig config = loadSimConfig(std::string(HAIR_SIM_REPO_ROOT) + "/config/hair_sim.yaml");
  const bench::MotionRun run(config, static_cast<int>(state.range(0)), Simulator::StepPath::Lanes, 1,
                             kWarmupSubsteps);
  const Simulator& sim = run.sim;
  const Iso3& pose = run.pose;
  std::vector<Vec3> points;
  sim.positionsWorld(pose, points);
  std::vector<Ellipsoid> bodies;
  for (std::size_t b = 0; b < config.bodies.size(); ++b)
    bodies.push_back(config.bodies[b].shape.transformed(run.body_frames[b]));
  HairMeshBuilder builder(sim.hairstyle(), HairMeshOptions{});
  builder.setThreads(static_cast<int>(state.range(1)));
  const Ellipsoid scalp = sim.hairstyle().scalp.transformed(pose);
  for (auto _ : state) {
    builder.build(points, sim.stripOffsets(), scalp, bodies);
    benchmark::DoNotOptimize(builder.meshes().data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * builder.vertexCount());
  state.counters["vertices"] = builder.vertexCount();
  state.counters["projected"] = builder.projectedVertices();
}
BENCHMARK(BM_MeshBuild)
    ->Args({100, 1})
    ->Args({1000, 1})
    ->Args({1000, 2})
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();

}  // namespace
