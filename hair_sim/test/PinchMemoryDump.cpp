/// Prints a hash of the control points after every substep of strips held in pinches between spheres, with
/// the springs on (so that resolveCollisions' band projection and relaxStrip ask escapeBodies again for the
/// same point), for a set of sphere sizes, strip widths and gusts. Built twice: against hair_sim_core (pinch
/// searches remembered within a sweep) and with Simulator.cpp compiled with -DHAIR_SIM_NO_PINCH_MEMORY (every
/// search anew); the test PinchMemoryGivesTheSameBits compares the two outputs.
///
/// The spheres sit on the axes about the roots (centres O +- c e_i, c = 0.1 m, segments of 0.1 m): with all
/// six of radius 0.095 m every end lies inside one (no clear direction: the search returns the least
/// penetrating one); with the three on the positive axes of 0.07 or 0.06 m the corner between them is clear
/// but the escape's first candidates are not (the search finds a clear direction, and the arc from there is
/// searched for each new direction asked). Both kinds are remembered and found again here: the test fails
/// when a remembered search returns its direction without the arc, or its first candidate instead of the
/// least penetrating direction (tried). 288 lines (12 substeps of 24 set-ups).
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <vector>

#include "hair_sim/core/Simulator.hpp"

using namespace hair_sim;

namespace {

void hashBytes(std::uint64_t& h, const void* data, std::size_t n) {
  const unsigned char* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 1099511628211ULL;
}

/// Strips of `columns` x 4 hanging straight down from roots `spacing` apart about O = (0, 0, 0.1).
Hairstyle pinchedStrips(int columns, double spacing, double d) {
  Hairstyle style;
  style.scalp = Ellipsoid(Vec3::Zero(), Mat3::Identity(), Vec3(0.1, 0.1, 0.1));
  Strip s;
  s.columns = columns;
  s.rows = 4;
  s.hair_length = 3.0 * d;
  s.width = spacing * (columns - 1) + 1e-3;
  s.points.resize(static_cast<std::size_t>(columns * s.rows));
  for (int c = 0; c < columns; ++c) {
    const Vec3 root(0.0, spacing * (c - 0.5 * (columns - 1)), 0.1);
    for (int r = 0; r < s.rows; ++r) s.point(r, c) = root + r * d * Vec3(0.0, 0.0, -1.0);
  }
  style.strips.push_back(s);
  return style;
}

}  // namespace

int main() {
  const Vec3 o(0.0, 0.0, 0.1);
  const double d = 0.1, c = 0.1;
  for (double positive_radius : {0.095, 0.07, 0.06}) {
    for (int columns : {2, 3}) {
      for (double spacing : {0.002, 0.01}) {
        for (double gust : {0.0, 20.0}) {
          const Hairstyle style = pinchedStrips(columns, spacing, d);
          const double margin = style.strips[0].thickness_margin;
          std::vector<Body> bodies;
          for (int axis = 0; axis < 3; ++axis)
            for (double sign : {-1.0, 1.0}) {
              const double radius = (sign > 0.0 ? positive_radius : 0.095) - margin;
              bodies.push_back(
                  Body{"ball", "world",
                       Ellipsoid(o + sign * c * Vec3::Unit(axis), Mat3::Identity(), Vec3::Constant(radius))});
            }
          Simulator sim(style, PhysicsParameters{}, bodies);
          StepInputs in;
          in.body_frames.assign(bodies.size(), Iso3::Identity());
          for (int n = 0; n < 12; ++n) {
            in.wind = Vec3(gust * std::sin(0.5 * n), gust * std::cos(0.3 * n), 0.0);
            sim.step(in);
            std::uint64_t h = 14695981039346656037ULL;
            hashBytes(h, sim.positionsHead().data(), sim.positionsHead().size() * sizeof(Vec3));
            std::printf("radius %.3f columns %d spacing %.3f gust %.0f substep %2d: %016llx\n",
                        positive_radius, columns, spacing, gust, n, static_cast<unsigned long long>(h));
          }
        }
      }
    }
  }
  return 0;
}
