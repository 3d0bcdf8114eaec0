/// Tessellation cost per vertex of the three methods on a synthetic 100-strip hairstyle (2 x 5 control
/// points per strip, curved, hair length 0.25-0.4 m) at the default level of detail. items_per_second
/// counts vertices, so 1e9 / items_per_second is the time per vertex in ns.
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "hair_sim/core/geometry/Tessellator.hpp"

namespace {

using hair_sim::LevelOfDetail;
using hair_sim::StripMesh;
using hair_sim::TessellationMethod;
using hair_sim::Tessellator;
using hair_sim::Vec3;

struct SyntheticStrip {
  std::vector<Vec3> points;
  double hair_length = 0.0;
};

constexpr int kStrips = 100;
constexpr int kColumns = 2;
constexpr int kRows = 5;

/// Strips rooted on a 0.1 m sphere, hanging down and outwards with a bend; deterministic.
std::vector<SyntheticStrip> makeHairstyle() {
  std::vector<SyntheticStrip> strips(kStrips);
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
    SyntheticStrip& strip = strips[static_cast<std::size_t>(i)];
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

/// The hairstyle in one call (the batch form of tessellate, as HairMeshBuilder calls it), or with
/// per_strip one call per strip.
void runTessellation(benchmark::State& state, TessellationMethod method, LevelOfDetail level = {},
                     bool per_strip = false) {
  const std::vector<SyntheticStrip> strips = makeHairstyle();
  Tessellator tessellator(level, method);
  std::vector<StripMesh> meshes(strips.size());
  std::vector<hair_sim::StripInput> inputs(strips.size());
  std::int64_t vertices = 0;
  for (std::size_t i = 0; i < strips.size(); ++i) {  // warm caches and mesh storage
    tessellator.tessellate(strips[i].points, kColumns, kRows, strips[i].hair_length, meshes[i]);
    vertices += meshes[i].vertexCount();
    inputs[i] = {strips[i].points.data(), kColumns, kRows, strips[i].hair_length};
  }
  for (auto _ : state) {
    if (per_strip) {
      for (std::size_t i = 0; i < strips.size(); ++i) {
        tessellator.tessellate(strips[i].points.data(), kColumns, kRows, strips[i].hair_length, meshes[i]);
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
  runTessellation(state, TessellationMethod::ForwardDifferencing);
}
void BM_Tessellate_DeBoor(benchmark::State& state) { runTessellation(state, TessellationMethod::DeBoor); }
void BM_Tessellate_CachedBasis(benchmark::State& state) {
  runTessellation(state, TessellationMethod::CachedBasis);
}
/// CachedBasis one strip per call (no strips in lanes).
void BM_Tessellate_CachedBasisPerStrip(benchmark::State& state) {
  runTessellation(state, TessellationMethod::CachedBasis, {}, true);
}

/// CachedBasis at samples_along = the argument (the default level of detail has 4): the cost per vertex of
/// longer columns, where the work per strip and per column is shared by more vertices.
void BM_Tessellate_CachedBasisAlong(benchmark::State& state) {
  LevelOfDetail level;
  level.samples_along = static_cast<int>(state.range(0));
  runTessellation(state, TessellationMethod::CachedBasis, level);
}

BENCHMARK(BM_Tessellate_ForwardDifferencing);
BENCHMARK(BM_Tessellate_DeBoor);
BENCHMARK(BM_Tessellate_CachedBasis);
BENCHMARK(BM_Tessellate_CachedBasisPerStrip);
BENCHMARK(BM_Tessellate_CachedBasisAlong)->Arg(4)->Arg(8)->Arg(16)->Arg(32);

}  // namespace
