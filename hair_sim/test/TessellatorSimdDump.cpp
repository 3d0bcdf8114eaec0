/// Prints a hash of every CachedBasis output bit (positions, normals, tangents, v_param) for a set of strips,
/// shapes, levels of detail and hair lengths (clipped and not). Built twice: against hair_sim_core (AVX2
/// kernels when the CPU has AVX2, chosen at run time) and with Tessellator.cpp compiled with
/// -DHAIR_SIM_NO_AVX2 (SSE2 kernels); the test TessellatorSimdPathsBitIdentical compares the two outputs.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <vector>

#include "SimdDump.hpp"
#include "hair_sim/core/geometry/Tessellator.hpp"

using namespace hair_sim;
using simd_dump::curvedGrid;
using simd_dump::hashBytes;
using simd_dump::kHashBasis;

/// Adds every output bit of the mesh but u_param (positions, normals, tangents, v_param) to the hash.
void hashMesh(std::uint64_t& hash, const StripMesh& m) {
  hashBytes(hash, m.positions.data(), m.positions.size() * sizeof(Vec3));
  hashBytes(hash, m.normals.data(), m.normals.size() * sizeof(Vec3));
  hashBytes(hash, m.tangents.data(), m.tangents.size() * sizeof(Vec3));
  hashBytes(hash, m.v_param.data(), m.v_param.size() * sizeof(float));
}

int main() {
  Tessellator tessellator(LevelOfDetail{}, TessellationMethod::CachedBasis);
  StripMesh mesh;
  const LevelOfDetail levels[] = {{1, 1}, {2, 4}, {3, 5}, {4, 7}, {8, 8}};
  for (const LevelOfDetail& level : levels) {
    tessellator.setLevelOfDetail(level);
    for (int columns = 2; columns <= 5; ++columns) {
      for (int rows = 4; rows <= 7; ++rows) {
        for (int seed = 0; seed < 3; ++seed) {
          const std::vector<Vec3> grid = curvedGrid(columns, rows, seed, 0.3, 0.4, 0.2);
          for (double hair_length : {10.0, 0.05 * rows, 0.03 * rows}) {
            tessellator.tessellate(grid, columns, rows, hair_length, mesh);
            std::uint64_t hash = kHashBasis;
            hashMesh(hash, mesh);
            std::printf("level %d x %d, %d x %d, seed %d, length %.2f: %016llx\n", level.samples_across,
                        level.samples_along, columns, rows, seed, hair_length,
                        static_cast<unsigned long long>(hash));
          }
        }
      }
    }
  }
  // The batch form (strips in SIMD lanes on AVX2: four strips of two columns and one row count per kernel
  // call), against one call per strip in the baseline build: every strip of the loops above, in that order,
  // per level (runs of 2-column strips of one row count, then the other shapes between them).
  for (const LevelOfDetail& level : levels) {
    tessellator.setLevelOfDetail(level);
    std::vector<std::vector<Vec3>> grids;
    std::vector<StripInput> strips;
    for (int rows = 4; rows <= 7; ++rows) {
      for (int columns = 2; columns <= 3; ++columns) {
        for (int seed = 0; seed < 5; ++seed) {
          grids.push_back(curvedGrid(columns, rows, seed, 0.3, 0.4, 0.2));
        }
      }
    }
    std::size_t g = 0;
    for (int rows = 4; rows <= 7; ++rows) {
      for (int columns = 2; columns <= 3; ++columns) {
        for (int seed = 0; seed < 5; ++seed, ++g) {
          strips.push_back({grids[g].data(), columns, rows, seed == 4 ? 10.0 : (0.03 + 0.005 * seed) * rows});
        }
      }
    }
    std::vector<StripMesh> meshes(strips.size());
    tessellator.tessellate(strips.data(), strips.size(), meshes.data());
    for (std::size_t i = 0; i < meshes.size(); ++i) {
      const StripMesh& m = meshes[i];
      std::uint64_t hash = kHashBasis;
      hashMesh(hash, m);
      hashBytes(hash, m.u_param.data(), m.u_param.size() * sizeof(float));
      std::printf("batch, level %d x %d, strip %zu (%d x %d): %016llx\n", level.samples_across,
                  level.samples_along, i, strips[i].columns, strips[i].rows,
                  static_cast<unsigned long long>(hash));
    }
  }
  // Finite control points near the largest double: a segment overflows to infinity (the walk crosses the
  // hair length there) and a later one is NaN (inf - inf). Every path clips at the infinite segment.
  const double huge = std::numeric_limits<double>::max();
  for (int samples_along = 1; samples_along <= 8; ++samples_along) {
    tessellator.setLevelOfDetail(LevelOfDetail{1, samples_along});
    for (int rows = 4; rows <= 9; ++rows) {
      for (int columns = 2; columns <= 4; ++columns) {
        std::vector<Vec3> grid(static_cast<std::size_t>(columns * rows));
        for (int r = 0; r < rows; ++r) {
          for (int c = 0; c < columns; ++c) {
            grid[static_cast<std::size_t>(r * columns + c)] =
                Vec3(huge * (1.0 - 1e-16 * ((r * 7 + c) % 3)), 0.01 * r + 0.001 * c, 0.0);
          }
        }
        tessellator.tessellate(grid, columns, rows, 0.5, mesh);
        std::uint64_t hash = kHashBasis;
        hashBytes(hash, mesh.positions.data(), mesh.positions.size() * sizeof(Vec3));
        hashBytes(hash, mesh.v_param.data(), mesh.v_param.size() * sizeof(float));
        std::printf("overflow, level 1 x %d, %d x %d: %016llx\n", samples_along, columns, rows,
                    static_cast<unsigned long long>(hash));
      }
      // The same in the batch form: four different 2-column grids in lanes, one of them short of the hair
      // length (its walk never crosses while the others' overflow).
      std::vector<std::vector<Vec3>> grids(4, std::vector<Vec3>(static_cast<std::size_t>(2 * rows)));
      for (int l = 0; l < 4; ++l) {
        for (int r = 0; r < rows; ++r) {
          for (int c = 0; c < 2; ++c) {
            grids[l][static_cast<std::size_t>(r * 2 + c)] =
                l == 2 ? Vec3(0.01 * c, 0.001 * r, -0.01 * r)
                       : Vec3(huge * (1.0 - 1e-16 * ((r * 7 + c + l) % 3)) * (l == 3 ? 0.5 : 1.0),
                              0.01 * r + 0.001 * c, 0.0);
          }
        }
      }
      const StripInput strips[4] = {{grids[0].data(), 2, rows, 0.5},
                                    {grids[1].data(), 2, rows, 0.5},
                                    {grids[2].data(), 2, rows, 0.5},
                                    {grids[3].data(), 2, rows, 0.5}};
      StripMesh meshes[4];
      tessellator.tessellate(strips, 4, meshes);
      for (int l = 0; l < 4; ++l) {
        std::uint64_t hash = kHashBasis;
        hashBytes(hash, meshes[l].positions.data(), meshes[l].positions.size() * sizeof(Vec3));
        hashBytes(hash, meshes[l].v_param.data(), meshes[l].v_param.size() * sizeof(float));
        std::printf("overflow batch, level 1 x %d, 2 x %d, strip %d: %016llx\n", samples_along, rows, l,
                    static_cast<unsigned long long>(hash));
      }
    }
  }
  // Finite control points 1e300 apart across and 1e10 along: |du x dv|^2 is inf - inf = NaN while |dv|^2 is
  // in range, so every path must take the frames' fall-back (normals and tangents hashed too), one strip per
  // call and four in the batch (with three plain strips, and four such strips).
  std::vector<Vec3> nan_grid(10);
  std::vector<Vec3> plain(10);
  for (int r = 0; r < 5; ++r) {
    nan_grid[static_cast<std::size_t>(2 * r)] = Vec3(0.0, 1e10 * r, 1e10 * r);
    nan_grid[static_cast<std::size_t>(2 * r + 1)] = Vec3(0.0, 1e300, 1e300);
    plain[static_cast<std::size_t>(2 * r)] = Vec3(0.0, 0.0, -0.02 * r);
    plain[static_cast<std::size_t>(2 * r + 1)] = Vec3(0.01, 0.0, -0.02 * r);
  }
  auto hashAll = [](const StripMesh& m) {
    std::uint64_t hash = kHashBasis;
    hashMesh(hash, m);
    return static_cast<unsigned long long>(hash);
  };
  for (const LevelOfDetail& level :
       {LevelOfDetail{1, 1}, LevelOfDetail{1, 4}, LevelOfDetail{2, 4}, LevelOfDetail{3, 4}}) {
    tessellator.setLevelOfDetail(level);
    tessellator.tessellate(nan_grid, 2, 5, 3e10, mesh);
    std::printf("nan normal, level %d x %d: %016llx\n", level.samples_across, level.samples_along,
                hashAll(mesh));
    for (int variant = 0; variant < 2; ++variant) {
      StripInput strips[4];
      for (int l = 0; l < 4; ++l) {
        const bool nan_strip = variant == 0 || l == 0;
        strips[l] = {nan_strip ? nan_grid.data() : plain.data(), 2, 5, nan_strip ? 3e10 : 0.05};
      }
      StripMesh meshes[4];
      tessellator.tessellate(strips, 4, meshes);
      for (int l = 0; l < 4; ++l) {
        std::printf("nan normal batch, level %d x %d, variant %d, strip %d: %016llx\n", level.samples_across,
                    level.samples_along, variant, l, hashAll(meshes[l]));
      }
    }
  }
  return 0;
}
