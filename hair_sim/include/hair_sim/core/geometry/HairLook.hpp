#pragma once
/// Per-vertex colour and alpha that imitate the paper's alpha-mapped hair texture on tessellated strips
/// (ROS 1 rviz markers have no textures but honour per-vertex colour and alpha).
#include <cstdint>
#include <vector>

#include "hair_sim/core/TypeDefs.hpp"
#include "hair_sim/core/geometry/Tessellator.hpp"

namespace hair_sim {

/// Shading and pattern parameters (directions need not be unit; they are normalised).
struct HairLookParameters {
  Vec3 light_direction{0.5, 0.0, 1.0};  ///< toward the light: from above and in front (x forward, z up)
  Vec3 view_direction{1.0, 0.0, 0.2};   ///< toward the viewer: in front, slightly above
  int strands_per_strip = 8;            ///< stripes (strands) across the width of a strip, >= 1
  double stripe_contrast = 0.6;         ///< [0, 1]: 0 = uniform strip, 1 = fully transparent between strands
  double tip_fade_start = 0.7;          ///< [0, 1): fraction of the hair length where alpha starts to fade
  double root_darkening = 0.35;         ///< [0, 1]: brightness lost at the root (fades out over root_length)
  double root_length = 0.2;         ///< (0, 1]: fraction of the length over which the root darkening fades
  double specular_strength = 0.3;   ///< >= 0: weight of the (white) Kajiya-Kay highlight
  double specular_exponent = 40.0;  ///< >= 1: sharpness of the highlight
  double ambient = 0.3;             ///< [0, 1]: light received regardless of orientation
};

/// Colours StripMesh vertices. Deterministic: the same mesh, colour and seed give the same output.
///
/// Per vertex (T = unit tangent, L = unit light direction, V = unit view direction):
///  - Kajiya-Kay diffuse sin(T, L) = sqrt(1 - (T.L)^2), so a strand lit along its length is dark;
///  - Kajiya-Kay specular max(0, sin(T,L) sin(T,V) - (T.L)(T.V))^exponent: the cosine of the angle between V
///    and the cone of mirror directions around T (with L and V both pointing away from the hair, the cone
///    holds the directions whose T component is -(T.L)). This is the published formula
///    (T.L)(T.V) + sin sin written with L pointing from the light to the hair;
///  - brightness = base * (ambient + (1 - ambient) * diffuse) * stripe brightness * root darkening
///    + specular_strength * specular (white), clamped to [0, 1];
///  - alpha = base.a * stripe alpha * tip fade: the stripe profile of u (a sum of narrow bumps, one per
///    strand, with a per-strip pseudo-random phase and jitter from the seed, box-filtered over the vertex
///    spacing like a mip-mapped texture: a mesh too coarse to resolve the strands gets their mean alpha
///    instead of aliasing; samples_across >= 2 * strands_per_strip resolves them) and a smoothstep fade from
///    tip_fade_start to 0 at v = 1.
/// All channels are clamped to [0, 1]. Throws std::invalid_argument on bad parameters.
class HairLook {
 public:
  explicit HairLook(const HairLookParameters& parameters = HairLookParameters{});

  const HairLookParameters& parameters() const { return parameters_; }

  /// One RGBA per mesh vertex into colours (resized to mesh.vertexCount(); no allocation when reused).
  /// base: the strip's colour (channels clamped to [0, 1]); strip_seed: varies the stripe pattern between
  /// strips. Throws std::invalid_argument when the mesh arrays are inconsistent.
  void colorize(const StripMesh& mesh, const Rgba& base, std::uint32_t strip_seed,
                std::vector<Rgba>& colours) const;
  /// The stripe profile of every vertex column of `mesh` (at its u_param, averaged over the column spacing)
  /// as colorize() computes it: depends on the seed and mesh.n_u only, so a caller that colours the same
  /// strip every frame computes it once.
  void stripeProfiles(const StripMesh& mesh, std::uint32_t strip_seed, std::vector<double>& profiles) const;
  /// colorize() with the profiles of stripeProfiles() (same seed, same n_u): the same colours. Throws
  /// std::invalid_argument when profiles does not have mesh.n_u entries.
  void colorize(const StripMesh& mesh, const Rgba& base, const std::vector<double>& profiles,
                std::vector<Rgba>& colours) const;
  /// The lighting of colorize() alone (Kajiya-Kay diffuse and specular, root darkening), no stripes and no
  /// tip fade: alpha = base.a. The vertex colours under an alpha-mapped texture that carries the strands
  /// and the tip fade (HairTexture), as the rviz display draws them. Same sizes and errors as colorize().
  void shade(const StripMesh& mesh, const Rgba& base, std::vector<Rgba>& colours) const;

  /// Kajiya-Kay diffuse term sin(T, L) for unit T and L, in [0, 1].
  static double diffuse(const Vec3& tangent, const Vec3& light);
  /// Kajiya-Kay specular term (see the class comment) for unit T, L, V, in [0, 1].
  static double specular(const Vec3& tangent, const Vec3& light, const Vec3& view, double exponent);

  /// Stripe profile in [0, 1] at u in [0, 1] (1 on a strand centre, 0 between strands), averaged over
  /// [u - width / 2, u + width / 2] (width >= 0; 0 = point sample).
  double stripeProfile(double u, std::uint32_t strip_seed, double width = 0.0) const;
  /// Alpha factor of the tip fade at v (arc length fraction): 1 before tip_fade_start, 0 at v >= 1.
  double tipFade(double v) const;
  /// Brightness factor of the root darkening at v: 1 - root_darkening at the root, 1 after root_length.
  double rootFactor(double v) const;

  /// Strand mode (LINE_LIST): `strands` hair strands across the strip at u = (k + 1/2) / strands, each a
  /// polyline along the mesh rows (linear interpolation between the mesh columns). Appends pairs of points
  /// (segment start, segment end) to points, skipping zero-length segments (clipped tips). When colours is
  /// not null (one per mesh vertex), point_colours receives the interpolated colour of every appended point.
  /// Throws std::invalid_argument when strands < 1 or the sizes are inconsistent.
  static void strandLines(const StripMesh& mesh, int strands, std::vector<Vec3>& points,
                          const std::vector<Rgba>* colours = nullptr,
                          std::vector<Rgba>* point_colours = nullptr);
  /// Same at explicit u values (each in [0, 1]).
  static void strandLines(const StripMesh& mesh, const std::vector<double>& u_values,
                          std::vector<Vec3>& points, const std::vector<Rgba>* colours = nullptr,
                          std::vector<Rgba>* point_colours = nullptr);

 private:
  /// stripeProfile of vertex column iu (its u_param, box-filtered over the column spacing).
  double columnProfile(const StripMesh& mesh, int iu, std::uint32_t strip_seed) const;
  /// pattern: stripes and tip fade, the stripe profile of column iu from profiles[iu] or, when profiles is
  /// null, computed; otherwise (shade) neither.
  void colour(const StripMesh& mesh, const Rgba& base, std::uint32_t strip_seed, bool pattern,
              const double* profiles, std::vector<Rgba>& colours) const;

  HairLookParameters parameters_;
  Vec3 light_;
  Vec3 view_;
};

}  // namespace hair_sim
