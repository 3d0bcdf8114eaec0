/// Tessellation cost per vertex of the three methods on the default hairstyle
/// (config/hairstyles/default.yaml: 100 strips of 2 x 5 control points; in two columns of three the hair
/// length ends in the last span, so the column is clipped there) at the default level of detail, and
/// CachedBasis on a synthetic hairstyle of the same shape whose columns are never clipped. items_per_second
/// counts vertices, so 1e9 / items_per_second is the time per vertex in ns.
#include <benchmark/benchmark.h>

#include <cmath>
#include <string>
#include <vector>

#include "hair_sim/core/geometry/Tessellator.hpp"
#include "hair_sim/core/model/HairstyleIO.hpp"

namespace {

using hair_sim::LevelOfDetail;
using hair_sim::StripMesh;
using hair_sim::TessellationMethod;
using hair_sim::Tessellator;
using hair_sim::Vec3;

struct BenchStrip {
  std::vector<Vec3> points;
  double hair_length = 0.0;
  int columns = 2;
  int rows = 5;
};

constexpr int kStrips = 100;
constexpr int kColumns = 2;
constexpr int kRows = 5;

/// Strips rooted on a 0.1 m sphere, hanging down and outwards with a bend; deterministic. Each hair length
/// is the length of its control polygon, longer than the surface's columns: nothing is clipped.
std::vector<BenchStrip> syntheticHairstyle() {
  std::vector<BenchStrip> strips(kStrips);
  const double pi = std::acos(-1.0);
  for (int i = 0; i < kStrips; ++i) {
    const double azimuth = 2.0 * pi * i / kStrips;
    const double elevation = 0.3 + 0.6 * std::fmod(0.618034 * i, 1.0);
    const double length = 0.25 + 0.15 * std::fmod(0.381966 * i + 0.2, 1.0);
    const double segment = length / (kRows - 1);
    const Vec3 radial(std::cos(azimuth) * std::cos(elevation), std::sin(azimuth) * std::cos(elevation),
                      std::sin(elevation));
    const Vec3 side(-std::sin(azimuth), std::cos(azimuth), 0.0);
    const Vec3 outward(std::cos(azimuth), std::sin(azimuth), 0.0);
    BenchStrip& strip = strips[static_cast<std::size_t>(i)];
    strip.hair_length = length;
    strip.points.resize(kColumns * kRows);
    for (int c = 0; c < kColumns; ++c) {
      Vec3 p = 0.1 * radial + (c - 0.5) * 0.02 * side;
      for (int r = 0; r < kRows; ++r) {
        strip.points[static_cast<std::size_t>(r * kColumns + c)] = p;
        const double bend = 0.2 + 0.35 * r + 0.05 * c;  // from outward towards down
        p += segment *
             (std::cos(bend) * outward - std::sin(bend) * Vec3::UnitZ() + 0.1 * std::sin(3.0 * r + i) * side)
                 .normalized();
      }
    }
  }
  return strips;
}

/// The default hairstyle (the node's, from config/), read once.
const std::vector<BenchStrip>& defaultHairstyle() {
  static const std::vector<BenchStrip> strips = [] {
    const hair_sim::Hairstyle hairstyle =
        hair_sim::loadHairstyle(std::string(HAIR_SIM_REPO_ROOT) + "/config/hairstyles/default.yaml");
    std::vector<BenchStrip> out;
    for (const hair_sim::Strip& strip : hairstyle.strips) {
      out.push_back({strip.points, strip.hair_length, strip.columns, strip.rows});
    }
    return out;
  }();
  return strips;
}

/// The hairstyle in one call (the batch form of tessellate, as HairMeshBuilder calls it), or with
/// per_strip one call per strip.
void runTessellation(benchmark::State& state, const std::vector<BenchStrip>& strips,
                     TessellationMethod method, LevelOfDetail level = {}, bool per_strip = false) {
  Tessellator tessellator(level, method);
  std::vector<StripMesh> meshes(strips.size());
  std::vector<hair_sim::StripInput> inputs(strips.size());
  std::int64_t vertices = 0;
  for (std::size_t i = 0; i < strips.size(); ++i) {  // warm caches and mesh storage
    const BenchStrip& strip = strips[i];
    tessellator.tessellate(strip.points, strip.columns, strip.rows, strip.hair_length, meshes[i]);
    vertices += meshes[i].vertexCount();
    inputs[i] = {strip.points.data(), strip.columns, strip.rows, strip.hair_length};
  }
  for (auto _ : state) {
    if (per_strip) {
      for (std::size_t i = 0; i < inputs.size(); ++i) {
        const hair_sim::StripInput& in = inputs[i];
        tessellator.tessellate(in.control_points, in.columns, in.rows, in.hair_length, meshes[i]);
      }
    } else {
      tessellator.tessellate(inputs.data(), inputs.size(), meshes.data());
    }
    benchmark::DoNotOptimize(meshes.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * vertices);
  state.counters["vertices_per_hairstyle"] = static_cast<double>(vertices);
}

void BM_Tessellate_ForwardDifferencing(benchmark::State& state) {
  runTessellation(state, defaultHairstyle(), TessellationMethod::ForwardDifferencing);
}
void BM_Tessellate_DeBoor(benchmark::State& state) {
  runTessellation(state, defaultHairstyle(), TessellationMethod::DeBoor);
}
void BM_Tessellate_CachedBasis(benchmark::State& state) {
  runTessellation(state, defaultHairstyle(), TessellationMethod::CachedBasis);
}
/// CachedBasis one strip per call (no strips in lanes).
void BM_Tessellate_CachedBasisPerStrip(benchmark::State& state) {
  runTessellation(state, defaultHairstyle(), TessellationMethod::CachedBasis, {}, true);
}
/// CachedBasis on the synthetic hairstyle, whose columns are never clipped (the benchmarks' hairstyle until
/// 2026-11-26).
void BM_Tessellate_CachedBasisUnclipped(benchmark::State& state) {
  runTessellation(state, syntheticHairstyle(), TessellationMethod::CachedBasis);
}

/// CachedBasis at samples_along = the argument (the default level of detail has 4): the cost per vertex of
/// longer columns, where the work per strip and per column is shared by more vertices.
void BM_Tessellate_CachedBasisAlong(benchmark::State& state) {
  LevelOfDetail level;
  level.samples_along = static_cast<int>(state.range(0));
  runTessellation(state, defaultHairstyle(), TessellationMethod::CachedBasis, level);
}

BENCHMARK(BM_Tessellate_ForwardDifferencing);
BENCHMARK(BM_Tessellate_DeBoor);
BENCHMARK(BM_Tessellate_CachedBasis);
BENCHMARK(BM_Tessellate_CachedBasisPerStrip);
BENCHMARK(BM_Tessellate_CachedBasisUnclipped);
BENCHMARK(BM_Tessellate_CachedBasisAlong)->Arg(4)->Arg(8)->Arg(16)->Arg(32);

}  // namespace
