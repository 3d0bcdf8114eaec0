/// Prints a hash of every HairLook output bit (colorize with and without precomputed stripe profiles, shade)
/// for a set of tessellated strips, levels of detail, hair lengths, colours and look parameters (the integer
/// specular exponent by repeated squaring and a fractional one by pow). Built twice: against hair_sim_core
/// (the lighting compiled for AVX2, chosen at run time when the CPU has it) and with HairLook.cpp compiled
/// with -DHAIR_SIM_NO_AVX2 (the x86-64 baseline alone); the test HairLookSimdPathsBitIdentical compares the
/// two outputs.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <vector>

#include "SimdDump.hpp"
#include "hair_sim/core/geometry/HairLook.hpp"
#include "hair_sim/core/geometry/Tessellator.hpp"

using namespace hair_sim;
using simd_dump::curvedGrid;
using simd_dump::hashBytes;
using simd_dump::kHashBasis;

int main() {
  HairLookParameters fractional;
  fractional.specular_exponent = 37.5;
  fractional.stripe_contrast = 0.4;
  fractional.light_direction = Vec3(0.3, -0.8, 0.5);
  HairLookParameters dark;
  dark.root_darkening = 0.9;
  dark.root_length = 0.3;
  dark.tip_fade_start = 0.2;
  dark.specular_strength = 2.0;
  dark.ambient = 0.0;
  const HairLookParameters looks[] = {HairLookParameters{}, fractional, dark};
  const Rgba colours[] = {Rgba{0.35f, 0.22f, 0.12f, 0.9f}, Rgba{1.5f, -0.2f, 0.5f, 1.0f}};
  const LevelOfDetail levels[] = {{1, 1}, {2, 4}, {3, 7}, {8, 8}};  // {8, 8}: columns of 153 vertices
  Tessellator tessellator;
  StripMesh mesh;
  std::vector<Rgba> out;
  std::vector<double> profiles;
  for (int l = 0; l < 3; ++l) {
    const HairLook look(looks[l]);
    for (const LevelOfDetail& level : levels) {
      tessellator.setLevelOfDetail(level);
      for (int columns = 2; columns <= 4; ++columns) {
        for (int rows = 4; rows <= 20; rows += 8) {
          for (int seed = 0; seed < 3; ++seed) {
            const std::vector<Vec3> grid = curvedGrid(columns, rows, seed, 0.3 + seed, 0.9, 1.2);
            for (double hair_length : {10.0, 0.05 * rows}) {
              tessellator.tessellate(grid, columns, rows, hair_length, mesh);
              for (int c = 0; c < 2; ++c) {
                std::uint64_t hash = kHashBasis;
                look.colorize(mesh, colours[c], static_cast<std::uint32_t>(seed * 7919), out);
                hashBytes(hash, out.data(), out.size() * sizeof(Rgba));
                look.stripeProfiles(mesh, 12345U, profiles);
                look.colorize(mesh, colours[c], profiles, out);
                hashBytes(hash, out.data(), out.size() * sizeof(Rgba));
                look.shade(mesh, colours[c], out);
                hashBytes(hash, out.data(), out.size() * sizeof(Rgba));
                std::printf("look %d, level %d x %d, %d x %d, seed %d, length %.2f, colour %d: %016llx\n", l,
                            level.samples_across, level.samples_along, columns, rows, seed, hair_length, c,
                            static_cast<unsigned long long>(hash));
              }
            }
          }
        }
      }
    }
  }
  return 0;
}
