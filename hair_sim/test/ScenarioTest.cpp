#include "hair_sim/tools/Scenario.hpp"

#include <gtest/gtest.h>

#include <cstring>

#include "TestUtil.hpp"

namespace hair_sim {
namespace {

TEST(ScenarioTest, HeadPassesThroughKeyframesC1) {
  Scenario s;
  s.head = {{0.0, Vec3(0, 0, 1), Vec3::Zero()},
            {1.0, Vec3(1, 0, 1), Vec3(0, 0, 0.5)},
            {2.0, Vec3(1, 1, 1), Vec3::Zero()}};
  for (const HeadKey& k : s.head) {
    const Iso3 p = s.headPose(k.t);
    EXPECT_NEAR((p.translation() - k.position).norm(), 0.0, 1e-12);
    EXPECT_TRUE(p.linear().isApprox(rotationFromRpy(k.rpy), 1e-12));
  }
  // C1 at the inner key: one-sided difference quotients agree; zero velocity at the ends.
  const double h = 1e-6;
  const Vec3 left = (s.headPose(1.0).translation() - s.headPose(1.0 - h).translation()) / h;
  const Vec3 right = (s.headPose(1.0 + h).translation() - s.headPose(1.0).translation()) / h;
  EXPECT_NEAR((left - right).norm(), 0.0, 1e-4);
  EXPECT_NEAR((left - Vec3(0.5, 0.5, 0.0)).norm(), 0.0, 1e-4);  // Catmull-Rom tangent
  EXPECT_NEAR((s.headPose(h).translation() - s.headPose(0).translation()).norm() / h, 0.0, 1e-4);
}

TEST(ScenarioTest, WindIsLinearBetweenKeysAndHolds) {
  Scenario s;
  s.head = {{0.0, Vec3::Zero(), Vec3::Zero()}};
  s.wind = {{1.0, Vec3(0, 0, 0)}, {3.0, Vec3(4, 0, 0)}};
  EXPECT_EQ(s.windVelocity(0.0), Vec3::Zero());
  EXPECT_NEAR(s.windVelocity(2.0).x(), 2.0, 1e-12);
  EXPECT_EQ(s.windVelocity(9.0), Vec3(4, 0, 0));
}

TEST(ScenarioTest, ShippedScenariosLoad) {
  for (const char* name :
       {"head_shake", "nod", "still", "violent_shake", "wind_sideways", "wind_from_behind"})
    EXPECT_NO_THROW(Scenario::load(test::repoPath(std::string("config/scenarios/") + name + ".yaml")))
        << name;
}

TEST(ScenarioTest, MalformedKeysAreNamed) {
  const std::string good =
      "duration: 2.0\noutput_rate: 30\nhead:\n  - {t: 0.0, position: [0, 0, 1.6], rpy: [0, 0, 0]}\n"
      "  - {t: 1.0, position: [0, 0, 1.6], rpy: [0, 0, 0.5]}\nwind:\n  - {t: 0.0, velocity: [1, 0, 0]}\n";
  const std::vector<test::FileEdit> cases = {
      {"duration: 2.0", "duration: -2", "duration", "-2"},
      {"output_rate: 30", "output_rate: x", "output_rate", "'x'"},
      {"t: 1.0", "t: 0.0", "head[1].t", ": 0 s is not"},
      {"rpy: [0, 0, 0.5]", "rpy: [0, 0]", "head[1].rpy", "[0, 0]"},
      {"position: [0, 0, 1.6], rpy: [0, 0, 0]}", "position: [0, 0, .nan], rpy: [0, 0, 0]}",
       "head[0].position[2]", ".nan"},
      {"velocity: [1, 0, 0]", "velocity: [1e9, 0, 0]", "wind[0].velocity", "1000 m/s"},
      {"velocity: [1, 0, 0]}", "velocity: [1, 0, 0], gust: 1}", "wind[0].gust", "unknown key"},
      {"head:\n", "heads: 1\nhead:\n", "heads", "unknown key"},
      // Found by fuzz_yaml: a list as a key (a bare YAML bad conversion before), far positions (NaN pose).
      {"velocity: [1, 0, 0]}", "velocity: [1, 0, 0], [2]: 1}", "wind[0]", "a key must be a name"},
      {"[0, 0, 1.6], rpy: [0, 0, 0.5]", "[1.0e308, 0, 1.6], rpy: [0, 0, 0.5]", "head[1].position", "10000 m"},
      {"rpy: [0, 0, 0.5]", "rpy: [0, 0, 5000]", "head[1].rpy", "1000 rad"},
      {"t: 1.0", "t: 1.0e-9", "head[1].t", "1e-06 s"},
  };
  test::expectEditsNamed(good, cases, [](const std::string& path) { Scenario::load(path); });
}

}  // namespace
}  // namespace hair_sim
