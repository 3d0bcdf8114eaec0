/// The node's wind commands (hair_sim_msgs/Wind through WindCommand): ramps between commands, and the
/// relative turbulence on top of the mean, bounded however often a command comes.
#include "hair_sim/core/events/WindCommand.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace hair_sim {
namespace {

// The fluctuation's noise vector has components of at most 1.5, 1.5 and 0.5: relative to the mean speed
// it is at most turbulence x sqrt(1.5^2 + 1.5^2 + 0.5^2) / 1.5 = 1.46 turbulence.
double maxSpeed(double speed, double turbulence) { return speed * (1.0 + 1.46 * turbulence); }

TEST(WindCommandTest, RampsLinearlyFromThePreviousMeanFromItsStart) {
  WindCommand w;
  EXPECT_EQ(w.at(5.0), Vec3::Zero());
  w.set(10.0, Vec3(4.0, 0.0, 0.0), 0.0, 2.0);
  EXPECT_EQ(w.at(9.999), Vec3::Zero());  // before its start: the previous wind
  EXPECT_NEAR(w.at(11.0).x(), 2.0, 1e-12);
  EXPECT_EQ(w.at(12.0), Vec3(4.0, 0.0, 0.0));
  EXPECT_EQ(w.at(100.0), Vec3(4.0, 0.0, 0.0));
  // Half way through a ramp, a new command ramps from where the first one was, at once here.
  w.set(20.0, Vec3(0.0, 2.0, 0.0), 0.0, 4.0);
  w.set(22.0, Vec3::Zero(), 0.0, 0.0);
  EXPECT_NEAR((w.at(21.999) - Vec3(2.0, 1.0, 0.0)).norm(), 0.0, 1e-3);
  EXPECT_EQ(w.at(22.0), Vec3::Zero());  // turning the wind off
  EXPECT_EQ(w.at(30.0), Vec3::Zero());
  // settle: a ramp that was to start later (time went backwards) gives the last command at every time.
  w.set(50.0, Vec3(1.0, 1.0, 1.0), 0.5, 10.0);
  w.settle();
  EXPECT_EQ(w.mean(0.0), Vec3(1.0, 1.0, 1.0));
  EXPECT_EQ(w.turbulence(0.0), 0.5);
}

TEST(WindCommandTest, TurbulenceFluctuatesAboutTheMeanWithinItsBound) {
  WindCommand w;
  w.set(1e9, Vec3(3.0, 0.0, 0.0), 1.0, 0.0);
  double highest = 0.0, sum = 0.0;
  int n = 0;
  for (double t = 1e9; t < 1e9 + 600.0; t += 0.01, ++n) {
    const Vec3 v = w.at(t);
    highest = std::max(highest, v.norm());
    sum += v.x();
  }
  EXPECT_LE(highest, maxSpeed(3.0, 1.0));
  EXPECT_GT(highest, 4.0);         // it does fluctuate
  EXPECT_NEAR(sum / n, 3.0, 0.1);  // about the mean
  EXPECT_EQ(w.turbulence(1e9 + 1.0), 1.0);
}

// A teleoperation stack sends the same wind again and again, each within the previous one's ramp. The
// turbulence used to be sampled into the start of the next ramp and fluctuated again there: 3 m/s with
// turbulence 0.3, ramp 1 s, sent at 30 Hz, reached 1e106 m/s within a minute (turbulence 1 at 100 Hz:
// infinite, and the node's every substep refused).
TEST(WindCommandTest, RepeatedCommandsWithinTheirRampStayBounded) {
  struct Case {
    double turbulence, rate, ramp;
  };
  for (const Case c :
       {Case{0.3, 30.0, 1.0}, Case{1.0, 100.0, 1.0}, Case{10.0, 100.0, 1.0}, Case{2.0, 10.0, 0.5}}) {
    WindCommand w;
    double highest = 0.0;
    const double t0 = 1.7e9;
    for (int k = 0; k < static_cast<int>(60.0 * c.rate); ++k) {
      const double t = t0 + k / c.rate;
      w.set(t, Vec3(3.0, 0.0, 0.0), c.turbulence, c.ramp);
      for (int j = 0; j < 10; ++j) highest = std::max(highest, w.at(t + j / (10.0 * c.rate)).norm());
    }
    EXPECT_LE(highest, maxSpeed(3.0, c.turbulence))
        << "turbulence " << c.turbulence << " at " << c.rate << " Hz, ramp " << c.ramp << " s";
    EXPECT_NEAR(w.mean(t0 + 60.0).x(), 3.0, 1e-9);
  }
}

// A command's turbulence, like its velocity, takes effect from its start (its stamp) over its ramp: it
// used to switch on arrival, before the velocity it is relative to.
TEST(WindCommandTest, TurbulenceRampsWithTheVelocityFromTheStart) {
  WindCommand w;
  w.set(0.0, Vec3(2.0, 0.0, 0.0), 0.0, 0.0);
  w.set(10.0, Vec3(2.0, 0.0, 0.0), 0.8, 4.0);
  EXPECT_EQ(w.turbulence(9.0), 0.0);
  EXPECT_EQ(w.at(9.0), Vec3(2.0, 0.0, 0.0));  // steady until its start
  EXPECT_NEAR(w.turbulence(12.0), 0.4, 1e-12);
  EXPECT_EQ(w.turbulence(14.0), 0.8);
}

}  // namespace
}  // namespace hair_sim
