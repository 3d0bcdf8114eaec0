#include "hair_sim/core/geometry/HairTexture.hpp"

#include <gtest/gtest.h>

#include "TestUtil.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <vector>

namespace hair_sim {
namespace {

using test::expectInvalid;

/// Alpha of a texel column, averaged over the rows before the tip fade.
double columnAlpha(const HairTexture& texture, int column, double v_end) {
  double sum = 0.0;
  int n = 0;
  for (int row = 0; (row + 0.5) / texture.height() < v_end; ++row, ++n) sum += texture.texel(column, row).a;
  return sum / n;
}

TEST(HairTextureTest, SizeAndLayout) {
  const HairTexture texture(HairLook{}, 64, 128, 3U);
  EXPECT_EQ(texture.width(), 64);
  EXPECT_EQ(texture.height(), 128);
  ASSERT_EQ(texture.rgba().size(), 64U * 128U * 4U);
  const Rgba t = texture.texel(5, 7);
  const std::size_t k = (7U * 64U + 5U) * 4U;
  EXPECT_FLOAT_EQ(t.r, texture.rgba()[k] / 255.f);
  EXPECT_FLOAT_EQ(t.a, texture.rgba()[k + 3] / 255.f);
  EXPECT_FLOAT_EQ(t.r, t.g);  // grey: the colour comes from the vertices
  EXPECT_FLOAT_EQ(t.g, t.b);
}

TEST(HairTextureTest, StrandsAcrossTheStripFollowTheLooksStripeProfiles) {
  HairLookParameters parameters;
  parameters.strands_per_strip = 8;
  parameters.stripe_contrast = 0.8;
  const HairLook look(parameters);
  const int width = 128;
  const std::uint32_t seed = 11U;
  const HairTexture texture(look, width, 64, seed);
  // At the root (before any fade): alpha = 1 - c + c (1 - prod_k (1 - w_k p_k(u))), p_k the stripe profile of
  // layer k (its own strand count and seed, box-filtered over a texel).
  std::vector<HairLook> layers;
  for (int k = 0; k < HairTexture::kLayers; ++k) {
    HairLookParameters layer = parameters;
    layer.strands_per_strip = HairTexture::layerStrands(8, k);
    layers.emplace_back(layer);
  }
  EXPECT_EQ(HairTexture::layerStrands(8, 0), 8);
  EXPECT_EQ(HairTexture::layerStrands(8, 2), 35);
  double low = 1.0, high = 0.0;
  for (int i = 0; i < width; ++i) {
    double uncovered = 1.0;
    for (int k = 0; k < HairTexture::kLayers; ++k)
      uncovered *=
          1.0 - std::pow(HairTexture::kLayerWeight, k) *
                    layers[static_cast<std::size_t>(k)].stripeProfile(
                        (i + 0.5) / width, seed * 7919U + static_cast<std::uint32_t>(k), 1.0 / width);
    const double expected = 0.2 + 0.8 * (1.0 - uncovered);
    EXPECT_NEAR(texture.texel(i, 0).a, expected, 0.5 / 255 + 1e-6) << "column " << i;
    low = std::min(low, columnAlpha(texture, i, 0.5));
    high = std::max(high, columnAlpha(texture, i, 0.5));
  }
  EXPECT_LT(low, 0.3);    // gaps between strands: mostly transparent (the sheet alone: 1 - c = 0.2)
  EXPECT_GT(high, 0.95);  // strand centres: opaque
}

TEST(HairTextureTest, TipsFadeAtDifferentLengths) {
  HairLookParameters parameters;
  parameters.tip_fade_start = 0.7;
  parameters.stripe_contrast = 1.0;  // strands only, no sheet between them
  const HairLook look(parameters);
  const HairTexture texture(look, 64, 256, 5U);
  const int last = texture.height() - 1;
  // No strand has started to fade before 0.7 of its shortest possible length.
  const int fade_free_rows =
      static_cast<int>(0.7 * (1.0 - HairTexture::kRaggedness * 0.3) * texture.height());
  int shortest = texture.height(), longest = 0;
  for (int i = 0; i < texture.width(); ++i) {
    const float root = texture.texel(i, 0).a;
    for (int row = 1; row < fade_free_rows; ++row) EXPECT_FLOAT_EQ(texture.texel(i, row).a, root);
    // Non-increasing along the hair, nothing left in the last row.
    for (int row = 1; row <= last; ++row) EXPECT_LE(texture.texel(i, row).a, texture.texel(i, row - 1).a);
    EXPECT_LE(texture.texel(i, last).a, 1.f / 255.f);
    if (root < 0.5f) continue;  // between strands
    // Where this strand falls below half its alpha.
    int half = 0;
    while (half < last && texture.texel(i, half).a >= 0.5f * root) ++half;
    shortest = std::min(shortest, half);
    longest = std::max(longest, half);
  }
  // Ragged tips: the strand ends are spread over a good part of the fade (0.3 x 256 texels x raggedness).
  EXPECT_GT(longest - shortest, 20);
}

TEST(HairTextureTest, DeterministicAndSeeded) {
  const HairLook look;
  const HairTexture a(look, 32, 32, 1U), b(look, 32, 32, 1U), c(look, 32, 32, 2U);
  EXPECT_EQ(a.rgba(), b.rgba());
  EXPECT_NE(a.rgba(), c.rgba());
}

TEST(HairTextureTest, BadInputsThrow) {
  const HairLook look;
  expectInvalid([&] { HairTexture t(look, 1, 64); }, "width and height must be in [2, 4096], got 1 x 64");
  expectInvalid([&] { HairTexture t(look, 64, 5000); }, "got 64 x 5000");
  const HairTexture texture(look, 4, 4);
  test::expectThrowNaming<std::out_of_range>([&] { texture.texel(4, 0); }, "texel (4, 0) is outside 4 x 4");
  test::expectThrowNaming<std::out_of_range>([&] { texture.texel(0, -1); }, "texel (0, -1) is outside 4 x 4");
}

}  // namespace
}  // namespace hair_sim
