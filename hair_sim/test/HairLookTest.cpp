#include "hair_sim/core/geometry/HairLook.hpp"

#include <gtest/gtest.h>

#include "TestUtil.hpp"

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "hair_sim/core/geometry/Tessellator.hpp"

namespace hair_sim {
namespace {

/// Flat strip hanging straight down (-z), `columns` wide along y, tessellated without clipping.
StripMesh hangingStrip(const LevelOfDetail& level, double hair_length = 0.4) {
  const int rows = 5;
  std::vector<Vec3> grid(2 * rows);
  for (int r = 0; r < rows; ++r) {
    grid[static_cast<std::size_t>(2 * r)] = Vec3(0.0, 0.0, -r * hair_length / (rows - 1));
    grid[static_cast<std::size_t>(2 * r + 1)] = Vec3(0.0, 0.03, -r * hair_length / (rows - 1));
  }
  Tessellator tessellator(level);
  StripMesh mesh;
  tessellator.tessellate(grid, 2, rows, hair_length, mesh);
  return mesh;
}

using test::expectInvalid;

TEST(HairLookTest, KajiyaKayDiffuseIsAnisotropic) {
  const Vec3 light = Vec3(0.0, 0.0, 1.0);
  EXPECT_NEAR(HairLook::diffuse(Vec3(0, 0, 1), light), 0.0, 1e-12);  // lit along the hair: dark
  EXPECT_NEAR(HairLook::diffuse(Vec3(0, 0, -1), light), 0.0, 1e-12);
  EXPECT_NEAR(HairLook::diffuse(Vec3(1, 0, 0), light), 1.0, 1e-12);  // lit across: bright
  // 60 degrees between T and L: sin = sqrt(3) / 2.
  EXPECT_NEAR(HairLook::diffuse(Vec3(std::sqrt(3.0) / 2, 0, 0.5), light), std::sqrt(3.0) / 2, 1e-12);
}

TEST(HairLookTest, KajiyaKaySpecularPeaksOnTheMirrorCone) {
  const double c = 0.5;  // 60 degrees between T and L
  const double s = std::sqrt(3.0) / 2.0;
  const Vec3 tangent(1, 0, 0);
  const Vec3 light(c, 0, s);
  // Mirror direction: same angle to the normal plane, opposite tangential component: cos = 1.
  EXPECT_NEAR(HairLook::specular(tangent, light, Vec3(-c, 0, s), 20.0), 1.0, 1e-12);
  // Any direction on the cone (rotated about T) is a mirror direction too.
  EXPECT_NEAR(HairLook::specular(tangent, light, Vec3(-c, s, 0), 20.0), 1.0, 1e-12);
  // Viewing from the light: sin^2 - cos^2 = 0.75 - 0.25 = 0.5.
  EXPECT_NEAR(HairLook::specular(tangent, light, light, 3.0), 0.125, 1e-12);
  // Along the hair: no highlight.
  EXPECT_NEAR(HairLook::specular(tangent, light, tangent, 3.0), 0.0, 1e-12);
}

TEST(HairLookTest, ChannelsStayInUnitRange) {
  HairLookParameters parameters;
  parameters.specular_strength = 5.0;  // would overflow without clamping
  parameters.specular_exponent = 1.0;
  parameters.stripe_contrast = 1.0;
  const HairLook look(parameters);
  std::mt19937 rng(4);
  std::normal_distribution<double> gauss;
  StripMesh mesh = hangingStrip(LevelOfDetail{8, 8});
  for (Vec3& t : mesh.tangents) {  // arbitrary orientations
    t = Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized();
  }
  std::vector<Rgba> colours;
  for (const Rgba& base : {Rgba{0.4f, 0.25f, 0.1f, 1.0f}, Rgba{2.0f, -1.0f, 0.5f, 3.0f}, Rgba{1, 1, 1, 1}}) {
    look.colorize(mesh, base, 17u, colours);
    ASSERT_EQ(colours.size(), mesh.positions.size());
    for (const Rgba& c : colours) {
      for (float channel : {c.r, c.g, c.b, c.a}) {
        EXPECT_GE(channel, 0.0f);
        EXPECT_LE(channel, 1.0f);
        EXPECT_TRUE(std::isfinite(channel));
      }
    }
  }
}

TEST(HairLookTest, AlphaFadesTowardTheTip) {
  HairLookParameters parameters;
  parameters.tip_fade_start = 0.6;
  const HairLook look(parameters);
  const StripMesh mesh = hangingStrip(LevelOfDetail{2, 8});
  std::vector<Rgba> colours;
  look.colorize(mesh, Rgba{0.3f, 0.2f, 0.1f, 1.0f}, 5u, colours);
  for (int iu = 0; iu < mesh.n_u; ++iu) {
    const float root_alpha = colours[static_cast<std::size_t>(mesh.index(iu, 0))].a;
    float previous = root_alpha;
    float at_start = -1.0f;
    for (int iv = 1; iv < mesh.n_v; ++iv) {
      const std::size_t i = static_cast<std::size_t>(mesh.index(iu, iv));
      const float v = mesh.v_param[i];
      if (v <= 0.6f) {
        EXPECT_FLOAT_EQ(colours[i].a, root_alpha);  // no fade before tip_fade_start
        at_start = colours[i].a;
      } else {
        EXPECT_LT(colours[i].a, previous);  // strictly decreasing after it
      }
      previous = colours[i].a;
    }
    EXPECT_GT(at_start, 0.0f);
    EXPECT_NEAR(colours[static_cast<std::size_t>(mesh.index(iu, mesh.n_v - 1))].a, 0.0f, 1e-6f);  // v = 1
  }
  EXPECT_DOUBLE_EQ(look.tipFade(0.3), 1.0);
  EXPECT_NEAR(look.tipFade(0.8), 0.5, 1e-12);  // smoothstep(0.5) = 0.5
  EXPECT_DOUBLE_EQ(look.tipFade(1.0), 0.0);
}

TEST(HairLookTest, RootIsDarker) {
  HairLookParameters parameters;
  parameters.root_darkening = 0.4;
  parameters.root_length = 0.25;
  parameters.specular_strength = 0.0;
  const HairLook look(parameters);
  EXPECT_DOUBLE_EQ(look.rootFactor(0.0), 0.6);
  EXPECT_DOUBLE_EQ(look.rootFactor(0.25), 1.0);
  EXPECT_DOUBLE_EQ(look.rootFactor(0.9), 1.0);
  const StripMesh mesh = hangingStrip(LevelOfDetail{2, 8});
  std::vector<Rgba> colours;
  look.colorize(mesh, Rgba{0.5f, 0.5f, 0.5f, 1.0f}, 1u, colours);
  // Same tangent everywhere (straight strip): brightness only varies with the root factor.
  const Rgba& root = colours[static_cast<std::size_t>(mesh.index(1, 0))];
  const Rgba& middle = colours[static_cast<std::size_t>(mesh.index(1, mesh.n_v / 2))];
  EXPECT_NEAR(root.r / middle.r, 0.6f, 1e-5f);
}

TEST(HairLookTest, StrandParallelToTheLightIsDarkerThanPerpendicular) {
  HairLookParameters parameters;
  parameters.light_direction = Vec3(0, 0, 1);
  parameters.specular_strength = 0.0;
  parameters.ambient = 0.2;
  parameters.root_darkening = 0.0;
  const HairLook look(parameters);
  StripMesh mesh = hangingStrip(LevelOfDetail{1, 1});
  std::vector<Rgba> parallel;
  look.colorize(mesh, Rgba{0.8f, 0.6f, 0.4f, 1.0f}, 3u, parallel);  // hanging: tangent -z, light +z
  for (Vec3& t : mesh.tangents) {
    t = Vec3(1, 0, 0);
  }
  std::vector<Rgba> perpendicular;
  look.colorize(mesh, Rgba{0.8f, 0.6f, 0.4f, 1.0f}, 3u, perpendicular);
  for (std::size_t i = 0; i < parallel.size(); ++i) {
    // ambient only versus full diffuse: ratio 0.2.
    EXPECT_NEAR(parallel[i].r / perpendicular[i].r, 0.2f, 1e-5f);
    EXPECT_FLOAT_EQ(parallel[i].a, perpendicular[i].a);  // shading does not touch alpha
  }
}

TEST(HairLookTest, StripesMakeAlphaVaryAcrossTheStrip) {
  HairLookParameters parameters;
  parameters.strands_per_strip = 4;
  parameters.stripe_contrast = 0.8;
  const HairLook look(parameters);
  const StripMesh mesh = hangingStrip(LevelOfDetail{32, 2});  // fine enough to resolve 4 strands
  std::vector<Rgba> colours;
  look.colorize(mesh, Rgba{0.3f, 0.2f, 0.1f, 1.0f}, 9u, colours);
  float low = 1.0f;
  float high = 0.0f;
  int peaks = 0;
  for (int iu = 0; iu < mesh.n_u; ++iu) {
    const float a = colours[static_cast<std::size_t>(mesh.index(iu, 1))].a;
    low = std::min(low, a);
    high = std::max(high, a);
    if (iu > 0 && iu + 1 < mesh.n_u) {
      const float left = colours[static_cast<std::size_t>(mesh.index(iu - 1, 1))].a;
      const float right = colours[static_cast<std::size_t>(mesh.index(iu + 1, 1))].a;
      peaks += a > left && a >= right;
    }
  }
  EXPECT_GT(high - low, 0.5f);
  EXPECT_LT(low, 1.0f - 0.8f + 0.05f);  // between strands: down to 1 - contrast
  EXPECT_EQ(peaks, 4);                  // one bump per strand
}

TEST(HairLookTest, StripePatternIsDeterministicAndDiffersBetweenStrips) {
  const HairLook look, another;
  double difference = 0.0;
  for (int i = 0; i <= 100; ++i) {
    const double u = i / 100.0;
    EXPECT_EQ(look.stripeProfile(u, 7u), another.stripeProfile(u, 7u));
    difference += std::abs(look.stripeProfile(u, 7u) - look.stripeProfile(u, 8u));
    EXPECT_GE(look.stripeProfile(u, 7u), 0.0);
    EXPECT_LE(look.stripeProfile(u, 7u), 1.0);
  }
  EXPECT_GT(difference, 1.0);
  // Box filtering: a footprint as wide as the strip gives the mean coverage, 8 bumps of area
  // 0.35 / 8 * 16 / 15 each (when none leaves [0, 1]).
  EXPECT_NEAR(look.stripeProfile(0.5, 7u, 1.0), 0.35 * 16.0 / 15.0, 0.06);
  const StripMesh mesh = hangingStrip(LevelOfDetail{2, 2});
  std::vector<Rgba> first;
  std::vector<Rgba> second;
  look.colorize(mesh, Rgba{0.3f, 0.2f, 0.1f, 1.0f}, 11u, first);
  look.colorize(mesh, Rgba{0.3f, 0.2f, 0.1f, 1.0f}, 11u, second);
  for (std::size_t i = 0; i < first.size(); ++i) {
    EXPECT_EQ(first[i].r, second[i].r);
    EXPECT_EQ(first[i].a, second[i].a);
  }
}

TEST(HairLookTest, StrandLinesFollowTheMesh) {
  const StripMesh mesh = hangingStrip(LevelOfDetail{2, 4});
  std::vector<Vec3> points;
  HairLook::strandLines(mesh, 4, points);
  ASSERT_EQ(points.size(), 4u * (mesh.n_v - 1) * 2u);  // pairs for every segment of every strand
  // Strand 0 at u = 1/8: 1/8 of the way from column 0 (y = 0) to the last (y = 0.03).
  EXPECT_NEAR(points[0].y(), 0.03 / 8, 1e-12);
  EXPECT_NEAR(points[0].z(), 0.0, 1e-12);
  for (std::size_t i = 0; i + 2 < points.size(); i += 2) {
    EXPECT_GT((points[i + 1] - points[i]).norm(), 0.0);
    if ((i / 2) % (mesh.n_v - 1) != static_cast<std::size_t>(mesh.n_v - 2)) {
      EXPECT_EQ(points[i + 1], points[i + 2]);  // consecutive segments share their end points
    }
  }
  std::vector<Rgba> colours(mesh.positions.size(), Rgba{0.2f, 0.4f, 0.6f, 0.8f});
  std::vector<Vec3> more;
  std::vector<Rgba> point_colours;
  HairLook::strandLines(mesh, std::vector<double>{0.0, 1.0}, more, &colours, &point_colours);
  ASSERT_EQ(more.size(), 2u * (mesh.n_v - 1) * 2u);
  ASSERT_EQ(point_colours.size(), more.size());
  EXPECT_FLOAT_EQ(point_colours[3].b, 0.6f);
  EXPECT_NEAR(more[0].y(), 0.0, 1e-15);
  EXPECT_NEAR(more[more.size() - 1].y(), 0.03, 1e-15);
}

TEST(HairLookTest, StrandLinesSkipClippedTips) {
  const StripMesh mesh = hangingStrip(LevelOfDetail{1, 4}, 0.4);
  std::vector<Vec3> full;
  HairLook::strandLines(mesh, 1, full);
  // Same strip cut to half its length: the clipped half collapses to one point and is skipped.
  std::vector<Vec3> grid(10);
  for (int r = 0; r < 5; ++r) {
    grid[static_cast<std::size_t>(2 * r)] = Vec3(0.0, 0.0, -r * 0.1);
    grid[static_cast<std::size_t>(2 * r + 1)] = Vec3(0.0, 0.03, -r * 0.1);
  }
  Tessellator tessellator(LevelOfDetail{1, 4});
  StripMesh clipped;
  tessellator.tessellate(grid, 2, 5, 0.19, clipped);
  std::vector<Vec3> half;
  HairLook::strandLines(clipped, 1, half);
  EXPECT_EQ(full.size(), 2u * 16u);
  EXPECT_EQ(half.size(), 2u * 8u);
  EXPECT_NEAR(half.back().z(), -0.19, 1e-12);
}

TEST(HairLookTest, ShadeIsTheLightingOfColorizeWithoutPattern) {
  HairLookParameters parameters;
  parameters.view_direction = Vec3(0.3, 1.0, 0.1);
  const HairLook look(parameters);
  HairLookParameters plain_parameters = parameters;
  plain_parameters.stripe_contrast = 0.0;  // no stripes: colorize's rgb is then the lighting alone
  const HairLook plain(plain_parameters);
  const StripMesh mesh = hangingStrip(LevelOfDetail{3, 8});
  const Rgba base{0.3f, 0.2f, 0.1f, 0.8f};
  std::vector<Rgba> shaded, reference;
  look.shade(mesh, base, shaded);
  plain.colorize(mesh, base, 7u, reference);
  ASSERT_EQ(shaded.size(), static_cast<std::size_t>(mesh.vertexCount()));
  for (std::size_t i = 0; i < shaded.size(); ++i) {
    EXPECT_FLOAT_EQ(shaded[i].r, reference[i].r);
    EXPECT_FLOAT_EQ(shaded[i].g, reference[i].g);
    EXPECT_FLOAT_EQ(shaded[i].b, reference[i].b);
    EXPECT_FLOAT_EQ(shaded[i].a, 0.8f);  // no tip fade: the texture carries it
  }
  StripMesh bad = mesh;
  bad.tangents.pop_back();
  expectInvalid([&] { look.shade(bad, base, shaded); }, "HairLook::shade(...) : tangents");
}

TEST(HairLookTest, BadInputsThrow) {
  HairLookParameters parameters;
  parameters.strands_per_strip = 0;
  expectInvalid([&] { HairLook look(parameters); }, "strands_per_strip must be in [1, 10000], got 0");
  parameters = HairLookParameters{};
  parameters.stripe_contrast = 1.5;
  expectInvalid([&] { HairLook look(parameters); },
                "stripe_contrast must be in [0.000000, 1.000000], got 1.5");
  parameters = HairLookParameters{};
  parameters.tip_fade_start = 1.0;
  expectInvalid([&] { HairLook look(parameters); }, "tip_fade_start must be in [0.000000, 1.000000), got 1");
  parameters = HairLookParameters{};
  parameters.light_direction = Vec3::Zero();
  expectInvalid([&] { HairLook look(parameters); }, "light_direction must be a finite non-zero vector");
  parameters = HairLookParameters{};
  parameters.ambient = std::numeric_limits<double>::quiet_NaN();
  expectInvalid([&] { HairLook look(parameters); }, "ambient");

  const HairLook look;
  StripMesh mesh = hangingStrip(LevelOfDetail{});
  mesh.v_param.pop_back();
  std::vector<Rgba> colours;
  expectInvalid([&] { look.colorize(mesh, Rgba{}, 0u, colours); }, "must have 51 entries");
  StripMesh empty;
  expectInvalid([&] { look.colorize(empty, Rgba{}, 0u, colours); }, "got 0 x 0");
  std::vector<Vec3> points;
  const StripMesh good = hangingStrip(LevelOfDetail{});
  expectInvalid([&] { HairLook::strandLines(good, 0, points); }, "strands must be >= 1, got 0");
  expectInvalid([&] { HairLook::strandLines(good, std::vector<double>{0.5, 1.2}, points); }, "got 1.2");
  std::vector<Rgba> few(3);
  std::vector<Rgba> out;
  expectInvalid([&] { HairLook::strandLines(good, 2, points, &few, &out); },
                "one entry per vertex (51), got 3");
}

}  // namespace
}  // namespace hair_sim
