/// Prints a hash of the control points after every substep of strips held in pinches between spheres, with
/// the springs on (so that resolveCollisions' band projection and relaxStrip ask escapeBodies again for the
/// same point), for a set of sphere sizes, strip widths and gusts. Built twice: against hair_sim_core (pinch
/// searches remembered within a sweep) and with Simulator.cpp compiled with -DHAIR_SIM_NO_PINCH_MEMORY (every
/// search anew); the test PinchMemoryGivesTheSameBitsInPinches compares the two outputs.
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
#include <vector>

#include "SimdDump.hpp"
#include "TestUtil.hpp"
#include "hair_sim/core/Simulator.hpp"

using namespace hair_sim;

int main() {
  const Vec3 o(0.0, 0.0, 0.1);  // about the roots (test::hangingStrip)
  const double d = 0.1, c = 0.1;
  for (double positive_radius : {0.095, 0.07, 0.06}) {
    for (int columns : {2, 3}) {
      for (double spacing : {0.002, 0.01}) {
        for (double gust : {0.0, 20.0}) {
          const Hairstyle style = test::hangingStrip(columns, 4, d, 0.0, spacing);
          const double margin = style.strips[0].thickness_margin;
          const std::vector<Body> bodies = test::axisBalls(o, c, 0.095 - margin, positive_radius - margin);
          Simulator sim(style, PhysicsParameters{}, bodies);
          StepInputs in;
          in.body_frames.assign(bodies.size(), Iso3::Identity());
          for (int n = 0; n < 12; ++n) {
            in.wind = Vec3(gust * std::sin(0.5 * n), gust * std::cos(0.3 * n), 0.0);
            sim.step(in);
            const std::uint64_t h =
                simd_dump::hashOf(sim.positionsHead().data(), sim.positionsHead().size() * sizeof(Vec3));
            std::printf("radius %.3f columns %d spacing %.3f gust %.0f substep %2d: %016llx\n",
                        positive_radius, columns, spacing, gust, n, static_cast<unsigned long long>(h));
          }
        }
      }
    }
  }
  return 0;
}
