#include "hair_sim/core/model/HairstyleGenerator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "TestUtil.hpp"
#include "hair_sim/core/util/YamlReader.hpp"

namespace hair_sim {
namespace {

const Ellipsoid kScalp(Vec3::Zero(), Mat3::Identity(), Vec3(0.095, 0.075, 0.115));

TEST(HairstyleGeneratorTest, CoversTheScalpWithAboutNStripsInLayers) {
  GeneratorOptions o;
  const Hairstyle h = generateHairstyle(kScalp, o);
  EXPECT_NEAR(static_cast<double>(h.strips.size()), o.strips, 0.1 * o.strips);
  EXPECT_NO_THROW(h.validate("generated", 1e-9));  // roots exactly on the scalp
  std::set<std::string> rings;
  for (const Strip& s : h.strips) rings.insert(s.name.substr(0, s.name.find('s')));
  EXPECT_EQ(static_cast<int>(rings.size()), o.rings);
  // Roots all around: front, back, left and right of the head.
  bool front = false, back = false, left = false, right = false;
  for (const Strip& s : h.strips) {
    const Vec3& r = s.point(0, 0);
    front |= r.x() > 0.05;
    back |= r.x() < -0.05;
    left |= r.y() > 0.05;
    right |= r.y() < -0.05;
  }
  EXPECT_TRUE(front && back && left && right);
}

TEST(HairstyleGeneratorTest, LengthsVaryAndGrowTowardTheBack) {
  const Hairstyle h = generateHairstyle(kScalp, GeneratorOptions());
  double front_sum = 0, back_sum = 0;
  int front_n = 0, back_n = 0;
  std::set<double> lengths;
  for (const Strip& s : h.strips) {
    lengths.insert(s.hair_length);
    if (s.point(0, 0).x() > 0.03) front_sum += s.hair_length, ++front_n;
    if (s.point(0, 0).x() < -0.03) back_sum += s.hair_length, ++back_n;
    // The surface (a spline inside the control polygon) ends at the hair length, the polygon after it.
    EXPECT_LE(s.hair_length, s.columnLength(0));
    EXPECT_GT(s.hair_length, 0.9 * s.columnLength(0));
  }
  EXPECT_GT(lengths.size(), h.strips.size() / 2);
  ASSERT_GT(front_n, 0);
  ASSERT_GT(back_n, 0);
  EXPECT_GT(back_sum / back_n, 1.3 * front_sum / front_n);
}

TEST(HairstyleGeneratorTest, PartingSendsHairAwayFromItOnTop) {
  GeneratorOptions o;
  const Hairstyle h = generateHairstyle(kScalp, o);
  int away = 0, total = 0;
  for (const Strip& s : h.strips) {
    // The whole strip falls to the side of the parting its root centre is on.
    const Vec3 root = 0.5 * (s.point(0, 0) + s.point(0, s.columns - 1));
    if (root.z() < 0.08) continue;  // the top of the head only
    const Vec3 tip = 0.5 * (s.point(s.rows - 1, 0) + s.point(s.rows - 1, s.columns - 1));
    ++total;
    if ((root.y() >= o.parting_y) == (tip.y() > root.y())) ++away;
  }
  ASSERT_GT(total, 5);
  EXPECT_EQ(away, total);
}

TEST(HairstyleGeneratorTest, StyledHairStartsOutsideTheInflatedScalpAndObstacles) {
  GeneratorOptions o;
  const Ellipsoid neck(Vec3(-0.01, 0.0, -0.14), Mat3::Identity(), Vec3(0.055, 0.055, 0.08));
  const Hairstyle h = generateHairstyle(kScalp, o, {neck});
  for (const Strip& s : h.strips)
    for (int r = 1; r < s.rows; ++r)
      for (int c = 0; c < s.columns; ++c) {
        EXPECT_FALSE(kScalp.inflated(s.thickness_margin).contains(s.point(r, c))) << s.name;
        EXPECT_FALSE(neck.inflated(s.thickness_margin).contains(s.point(r, c))) << s.name;
      }
}

TEST(HairstyleGeneratorTest, SameSeedSameHairstyleOtherSeedOther) {
  GeneratorOptions o;
  const Hairstyle a = generateHairstyle(kScalp, o), b = generateHairstyle(kScalp, o);
  o.seed = 8;
  const Hairstyle c = generateHairstyle(kScalp, o);
  EXPECT_EQ(a.strips[3].hair_length, b.strips[3].hair_length);
  EXPECT_NE(a.strips[3].hair_length, c.strips[3].hair_length);
}

TEST(HairstyleGeneratorTest, RejectsBadOptions) {
  GeneratorOptions o;
  o.rows = 3;
  EXPECT_NE(test::errorOf([&] { generateHairstyle(kScalp, o); }).find("rows 3"), std::string::npos);
  o = GeneratorOptions();
  o.strips = 0;
  EXPECT_NE(test::errorOf([&] { generateHairstyle(kScalp, o); }).find("strips 0"), std::string::npos);
  o = GeneratorOptions();
  o.rings = 0;
  test::expectInvalid([&] { generateHairstyle(kScalp, o); }, "rings 0 < 1");
  o = GeneratorOptions();
  o.columns = 1;
  test::expectInvalid([&] { generateHairstyle(kScalp, o); }, "columns 1 < 2");
  // Each length named with its value.
  for (double bad : {0.0, -0.12, std::nan("")}) {
    o = GeneratorOptions();
    o.length_front = bad;
    test::expectInvalid([&] { generateHairstyle(kScalp, o); },
                        "length_front " + formatDouble(bad) + " m must be > 0");
    o = GeneratorOptions();
    o.length_back = bad;
    test::expectInvalid([&] { generateHairstyle(kScalp, o); },
                        "length_back " + formatDouble(bad) + " m must be > 0");
  }
  // Just inside the limits: one ring, hair a millimetre long.
  o = GeneratorOptions();
  o.rings = 1;
  o.length_front = 1e-3;
  o.length_back = 1e-3;
  EXPECT_NO_THROW(generateHairstyle(kScalp, o));
}

TEST(HairstyleGeneratorTest, RejectsGridsLargerThanTheLoaderTakes) {
  // hair_sim_generate used to write 65 columns and 300 rows, which hair_sim_offline then refused.
  GeneratorOptions o;
  o.columns = Strip::kMaxColumns + 1;
  test::expectInvalid([&] { generateHairstyle(kScalp, o); }, "columns 65 > 64");
  o = GeneratorOptions();
  o.rows = Strip::kMaxRows + 1;
  test::expectInvalid([&] { generateHairstyle(kScalp, o); }, "rows 257 > 256");
  // generatedStripCount is the count generateHairstyle makes (3 a ring at least), for a caller's caps.
  o = GeneratorOptions();
  EXPECT_EQ(generatedStripCount(o), static_cast<int>(generateHairstyle(kScalp, o).strips.size()));
  o.strips = 1;
  o.rings = 4;
  EXPECT_EQ(generatedStripCount(o), 12);
  EXPECT_EQ(generateHairstyle(kScalp, o).strips.size(), 12u);
}

TEST(HairstyleGeneratorTest, RejectsABodyInAFrameOtherThanTheHeadOrTheWorld) {
  // As the offline runner does; it was taken as fixed in the world.
  SimConfig config;
  config.bodies.push_back(
      {"torso", config.world_frame, Ellipsoid(Vec3(0, 0, 1.13), Mat3::Identity(), Vec3(0.11, 0.17, 0.27))});
  config.bodies.push_back(
      {"neck", "neck", Ellipsoid(Vec3(-0.01, 0, 1.45), Mat3::Identity(), Vec3(0.05, 0.05, 0.09))});
  Iso3 head = Iso3::Identity();
  head.translation() = Vec3(0, 0, 1.6);
  test::expectInvalid(
      [&] { generateHairstyle(config, head, GeneratorOptions()); },
      "bodies: body 'neck' is in frame 'neck': the generator knows only head_frame 'head' and "
      "world_frame 'world'");
  config.bodies.pop_back();
  EXPECT_NO_THROW(generateHairstyle(config, head, GeneratorOptions()));
}

}  // namespace
}  // namespace hair_sim
