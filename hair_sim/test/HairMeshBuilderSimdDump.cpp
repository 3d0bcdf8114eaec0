/// Prints a hash of the positions of every mesh vertex HairMeshBuilder builds, with the count of vertices
/// moved out of a body, for curved strips hanging through five bodies at three levels of detail (most
/// groups of four vertices out of reach of most bodies, some in reach but outside, some inside, some strips
/// so far out that their squared distances overflow). Built twice: against hair_sim_core (the bounding box
/// and reach test compiled for AVX2 too, chosen at load time) and with HairMeshBuilder.cpp compiled with
/// -DHAIR_SIM_NO_AVX2 (the x86-64 baseline alone); the test HairMeshBuilderSimdPathsBitIdentical compares the
/// two outputs.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <vector>

#include "SimdDump.hpp"
#include "hair_sim/core/geometry/HairMeshBuilder.hpp"
#include "hair_sim/core/model/Hairstyle.hpp"

using namespace hair_sim;
using simd_dump::curvedGrid;
using simd_dump::hashBytes;

int main() {
  Hairstyle style;
  style.scalp = Ellipsoid(Vec3::Zero(), Mat3::Identity(), Vec3(0.1, 0.1, 0.1));
  std::vector<Vec3> points;
  std::vector<int> offsets;
  for (int seed = 0; seed < 48; ++seed) {
    Strip strip;
    strip.columns = 2 + seed % 2;
    strip.rows = 5 + seed % 3;
    strip.points = curvedGrid(strip.columns, strip.rows, seed, 0.2 + 0.05 * (seed % 7), 0.5, 0.4);
    const double scale = seed == 17 ? 1e300 : 1.0;  // far out: its vertices overflow
    for (Vec3& p : strip.points) p = scale * (p + Vec3(0.03 * std::cos(seed), 0.03 * std::sin(seed), 0.0));
    strip.hair_length = 0.08 * (strip.rows - 1);
    offsets.push_back(static_cast<int>(points.size()));
    points.insert(points.end(), strip.points.begin(), strip.points.end());
    style.strips.push_back(strip);
  }
  const Mat3 tilt = Eigen::AngleAxisd(0.4, Vec3(0.3, 1.0, 0.2).normalized()).toRotationMatrix();
  const std::vector<Ellipsoid> bodies = {
      Ellipsoid(Vec3(0.12, 0.02, -0.12), tilt, Vec3(0.06, 0.04, 0.1)),
      Ellipsoid(Vec3(0.0, 0.0, -0.35), Mat3::Identity(), Vec3(0.25, 0.2, 0.06)),
      Ellipsoid(Vec3(-0.2, 0.1, -0.1), tilt.transpose(), Vec3(0.05, 0.05, 0.05)),
      Ellipsoid(Vec3(0.2, -0.15, -0.2), Mat3::Identity(), Vec3(0.1, 0.03, 0.08)),
      Ellipsoid(Vec3(5.0, 5.0, 5.0), Mat3::Identity(), Vec3(0.1, 0.1, 0.1)),  // out of every strip's reach
  };
  const LevelOfDetail levels[] = {{2, 4}, {1, 1}, {3, 7}};
  for (const LevelOfDetail& level : levels) {
    HairMeshOptions options;
    options.level_of_detail = level;
    HairMeshBuilder builder(style, options);
    builder.build(points, offsets, style.scalp, bodies);
    std::uint64_t hash = 1469598103934665603ULL;
    for (const StripMesh& mesh : builder.meshes())
      hashBytes(hash, mesh.positions.data(), mesh.positions.size() * sizeof(Vec3));
    std::printf("level %d x %d: %d vertices, %d moved out of a body, positions %016llx\n",
                level.samples_across, level.samples_along, builder.vertexCount(), builder.projectedVertices(),
                static_cast<unsigned long long>(hash));
  }
  return 0;
}
