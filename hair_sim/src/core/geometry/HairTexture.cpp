#include "hair_sim/core/geometry/HairTexture.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace hair_sim {

namespace {

constexpr double kTwoPi = 6.283185307179586;

/// Deterministic pseudo-random number in [0, 1) from a seed and an index (a 32-bit integer mix).
double unitHash(std::uint32_t seed, std::uint32_t index) {
  std::uint32_t x = seed * 0x9E3779B9U ^ (index + 0x7F4A7C15U) * 0x85EBCA6BU;
  x ^= x >> 16;
  x *= 0x7feb352dU;
  x ^= x >> 15;
  x *= 0x846ca68bU;
  x ^= x >> 16;
  return static_cast<double>(x) / 4294967296.0;
}

std::uint8_t toByte(double value) {
  return static_cast<std::uint8_t>(std::lround(255.0 * std::max(0.0, std::min(1.0, value))));
}

}  // namespace

HairTexture::HairTexture(const HairLook& look, int width, int height, std::uint32_t seed)
    : width_(width), height_(height) {
  if (width < 2 || width > 4096 || height < 2 || height > 4096) {
    throw std::invalid_argument(
        "HairTexture::HairTexture(...) : width and height must be in [2, 4096], got " +
        std::to_string(width) + " x " + std::to_string(height));
  }
  const HairLookParameters& p = look.parameters();
  const double contrast = p.stripe_contrast;
  const double texel = 1.0 / width;
  const double spread = kRaggedness * (1.0 - p.tip_fade_start);
  // Per layer and texel column: weighted strand profile, strand brightness, strand end e_k(u).
  struct Column {
    double profile[kLayers];
    double end[kLayers];
    double brightness[kLayers];
  };
  std::vector<Column> columns(static_cast<std::size_t>(width));
  for (int k = 0; k < kLayers; ++k) {
    HairLookParameters layer_parameters = p;
    layer_parameters.strands_per_strip = layerStrands(p.strands_per_strip, k);
    const HairLook layer(layer_parameters);
    const int strands = layer_parameters.strands_per_strip;
    const std::uint32_t layer_seed = seed * 7919U + static_cast<std::uint32_t>(k);
    const double weight = std::pow(kLayerWeight, k);
    // Strand ends: two sines at about the strand frequency with seeded phases.
    const double f1 = strands * (0.9 + 0.2 * unitHash(layer_seed, 1U));
    const double f2 = strands * (1.6 + 0.3 * unitHash(layer_seed, 2U));
    const double phase1 = kTwoPi * unitHash(layer_seed, 3U);
    const double phase2 = kTwoPi * unitHash(layer_seed, 4U);
    for (int i = 0; i < width; ++i) {
      const double u = (i + 0.5) * texel;
      Column& c = columns[static_cast<std::size_t>(i)];
      c.profile[k] = weight * layer.stripeProfile(u, layer_seed, texel);
      const int strand = std::min(strands - 1, static_cast<int>(u * strands));
      c.brightness[k] =
          1.0 - kBrightnessJitter * unitHash(layer_seed, 16U + static_cast<std::uint32_t>(strand));
      const double wave =
          0.5 + 0.25 * (std::sin(kTwoPi * f1 * u + phase1) + std::sin(kTwoPi * f2 * u + phase2));
      c.end[k] = 1.0 - spread * wave;
    }
  }
  rgba_.resize(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 4U);
  for (int j = 0; j < height; ++j) {
    const double v = (j + 0.5) / height;
    const double sheet = (1.0 - contrast) * look.tipFade(v);
    for (int i = 0; i < width; ++i) {
      const Column& c = columns[static_cast<std::size_t>(i)];
      double uncovered = 1.0, weights = 0.0, brightness = 0.0;
      for (int k = 0; k < kLayers; ++k) {
        const double a = c.profile[k] * look.tipFade(std::min(1.0, v / c.end[k]));
        uncovered *= 1.0 - a;
        weights += a;
        brightness += a * c.brightness[k];
      }
      const double coverage = 1.0 - uncovered;
      const double grey = (1.0 - 0.5 * contrast * (1.0 - coverage)) *
                          (weights > 1e-9 ? brightness / weights : 1.0 - 0.5 * kBrightnessJitter);
      const std::size_t t = (static_cast<std::size_t>(j) * static_cast<std::size_t>(width) + i) * 4U;
      rgba_[t] = rgba_[t + 1] = rgba_[t + 2] = toByte(grey);
      rgba_[t + 3] = toByte(sheet + contrast * coverage);
    }
  }
}

Rgba HairTexture::texel(int column, int row) const {
  if (column < 0 || column >= width_ || row < 0 || row >= height_) {
    throw std::out_of_range("HairTexture::texel(...) : texel (" + std::to_string(column) + ", " +
                            std::to_string(row) + ") is outside " + std::to_string(width_) + " x " +
                            std::to_string(height_));
  }
  const std::size_t k = (static_cast<std::size_t>(row) * static_cast<std::size_t>(width_) + column) * 4U;
  return Rgba{rgba_[k] / 255.f, rgba_[k + 1] / 255.f, rgba_[k + 2] / 255.f, rgba_[k + 3] / 255.f};
}

}  // namespace hair_sim
