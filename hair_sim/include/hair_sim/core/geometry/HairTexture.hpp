#pragma once
/// The paper's alpha-mapped hair texture, generated from a HairLook: what a viewer that can draw textures
/// (the rviz display HairDisplay) puts on the tessellated strips instead of per-vertex stripes.
#include <cstdint>
#include <vector>

#include "hair_sim/core/TypeDefs.hpp"
#include "hair_sim/core/geometry/HairLook.hpp"

namespace hair_sim {

/// One tile spans one strip: texel column i sits at u = (i + 1/2) / width across the strip (the mesh's
/// u_param), texel row j at v = (j + 1/2) / height along the hair (the mesh's v_param: arc length / hair
/// length), row 0 at the root. RGBA, 8 bits per channel, row-major.
///
/// Strands come in kLayers layers: layer k has n_k = n (2^k) + 2^k - 1 strands (n = the look's
/// strands_per_strip), its own seed, weight w_k = kLayerWeight^k, and the look's stripe profile p_k(u)
/// (HairLook::stripeProfile, box-filtered over one texel), so there are a few thick strands and more thin
/// ones in the gaps. Every strand ends at its own length: layer k fades as tipFade(v / e_k(u)), with e_k(u)
/// in [1 - kRaggedness (1 - tip_fade_start), 1] a smooth seeded function that varies from strand to strand
/// (ragged tips). With c the look's stripe_contrast:
///  - coverage s(u, v) = 1 - prod_k (1 - w_k p_k(u) tipFade(v / e_k(u)));
///  - alpha = (1 - c) tipFade(v) + c s(u, v): a sheet of opacity 1 - c between the strands, fading first;
///    at v = 1 everything has ended (alpha 0);
///  - grey level (r = g = b) = (1 - c (1 - s) / 2) times the strands' brightness (a seeded value per strand
///    in [1 - kBrightnessJitter, 1], averaged with the strands' weights): darker between the strands as in
///    HairLook::colorize.
/// The colour comes from the vertices (HairLook::shade), which the texture multiplies. Deterministic.
class HairTexture {
 public:
  /// Fraction of the tip fade over which the strand ends are spread.
  static constexpr double kRaggedness = 0.6;
  /// Largest brightness loss of a strand.
  static constexpr double kBrightnessJitter = 0.35;
  /// Strand layers and the weight ratio between successive ones.
  static constexpr int kLayers = 3;
  static constexpr double kLayerWeight = 0.7;
  /// Strands of layer k (n strands in layer 0).
  static int layerStrands(int n, int layer) { return n * (1 << layer) + (1 << layer) - 1; }

  /// width and height in [2, 4096]; throws std::invalid_argument otherwise.
  HairTexture(const HairLook& look, int width, int height, std::uint32_t seed = 1U);

  int width() const { return width_; }
  int height() const { return height_; }
  /// width * height * 4 bytes: r, g, b, a of texel (0, 0), then (1, 0), ...
  const std::vector<std::uint8_t>& rgba() const { return rgba_; }
  /// Texel at column i (across) and row j (along), channels in [0, 1]; throws std::out_of_range outside.
  Rgba texel(int column, int row) const;

 private:
  int width_;
  int height_;
  std::vector<std::uint8_t> rgba_;
};

}  // namespace hair_sim
