/// The node's checks of Wind messages and tf transforms (hair_sim/ros/InputChecks.hpp), without a master.
#include "hair_sim/ros/InputChecks.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace hair_sim {
namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

hair_sim_msgs::Wind wind(double x, double y, double z) {
  hair_sim_msgs::Wind w;
  w.velocity.x = x;
  w.velocity.y = y;
  w.velocity.z = z;
  return w;
}

TEST(InputChecksTest, WindNamesTheBadField) {
  EXPECT_EQ(checkWind(wind(1.0, 2.0, 3.0)), "");
  EXPECT_EQ(checkWind(wind(kNaN, 0.0, 0.0)), "velocity.x is nan");
  EXPECT_EQ(checkWind(wind(0.0, kInf, 0.0)), "velocity.y is inf");
  EXPECT_EQ(checkWind(wind(0.0, 0.0, -kInf)), "velocity.z is -inf");
  hair_sim_msgs::Wind w = wind(1.0, 0.0, 0.0);
  w.turbulence = kNaN;
  EXPECT_EQ(checkWind(w), "turbulence is nan");
  w.turbulence = -0.5;
  EXPECT_EQ(checkWind(w), "turbulence is -0.5, must be >= 0");
  w.turbulence = 10.0;  // (the fluctuation ten times the mean speed: taken)
  EXPECT_EQ(checkWind(w), "");
  w.turbulence = 1e306;  // (would make the wind infinite)
  EXPECT_EQ(checkWind(w), "turbulence is 1e+306, must be <= 10");
  w.turbulence = 0.2;
  w.ramp_time = -1.0;
  EXPECT_EQ(checkWind(w), "ramp_time is -1 s, must be >= 0");
  // 1,000 m/s is extreme but taken; faster is refused.
  EXPECT_EQ(checkWind(wind(0.0, 600.0, 800.0)), "");
  EXPECT_EQ(checkWind(wind(0.0, 600.0, 800.1)).find("velocity is 1000.0"), 0u);
}

geometry_msgs::TransformStamped transform(double x, double qx, double qy, double qz, double qw) {
  geometry_msgs::TransformStamped t;
  t.header.frame_id = "world";
  t.child_frame_id = "head";
  t.transform.translation.x = x;
  t.transform.rotation.x = qx;
  t.transform.rotation.y = qy;
  t.transform.rotation.z = qz;
  t.transform.rotation.w = qw;
  return t;
}

TEST(InputChecksTest, TransformsAreCheckedAndNormalised) {
  geometry_msgs::TransformStamped fixed;
  bool normalised = true;
  EXPECT_EQ(checkTransform(transform(0.5, 0.0, 0.0, 0.0, 1.0), &fixed, &normalised), "");
  EXPECT_FALSE(normalised);
  EXPECT_EQ(fixed.transform.translation.x, 0.5);
  EXPECT_EQ(checkTransform(transform(kNaN, 0.0, 0.0, 0.0, 1.0), &fixed, &normalised), "translation.x is nan");
  EXPECT_EQ(checkTransform(transform(0.0, 0.0, kInf, 0.0, 1.0), &fixed, &normalised), "rotation.y is inf");
  EXPECT_EQ(checkTransform(transform(0.0, 0.0, 0.0, 0.0, 0.0), &fixed, &normalised),
            "rotation is a zero quaternion (0, 0, 0, 0)");
  // A quaternion of norm 2 comes out unit, the same rotation.
  EXPECT_EQ(checkTransform(transform(0.0, 0.0, 0.0, 2.0 * std::sin(0.25), 2.0 * std::cos(0.25)), &fixed,
                           &normalised),
            "");
  EXPECT_TRUE(normalised);
  EXPECT_NEAR(fixed.transform.rotation.z, std::sin(0.25), 1e-15);
  EXPECT_NEAR(fixed.transform.rotation.w, std::cos(0.25), 1e-15);
}

}  // namespace
}  // namespace hair_sim
