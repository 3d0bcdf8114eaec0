#include "hair_sim/core/geometry/HairLook.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "../SimdDispatch.hpp"

// The lighting of a vertex column is compiled for the baseline and for AVX2 (SimdDispatch.hpp; test
// HairLookSimdPathsBitIdentical).

namespace hair_sim {

namespace {

/// Bump half-width as a fraction of the strand spacing 1 / strands (narrow: bumps never overlap, since
/// neighbouring centres stay at least (1 - 2 kJitter) / strands apart and 2 * kHalfWidth < 1 - 2 kJitter).
constexpr double kHalfWidth = 0.35;
/// Per-strand centre jitter amplitude (fraction of the spacing, +-) and per-strip phase amplitude (+-).
constexpr double kJitter = 0.12;
constexpr double kPhase = 0.3;

std::uint32_t mix(std::uint32_t x) {
  x ^= x >> 16;
  x *= 0x7feb352dU;
  x ^= x >> 15;
  x *= 0x846ca68bU;
  x ^= x >> 16;
  return x;
}

/// Deterministic pseudo-random number in [0, 1) from a seed and an index.
double unitHash(std::uint32_t seed, std::uint32_t index) {
  return static_cast<double>(mix(seed * 0x9E3779B9U + mix(index + 0x632BE5ABU))) / 4294967296.0;
}

/// Antiderivative of the bump (1 - t^2)^2 on [-1, 1], clamped outside: G(1) - G(-1) = 16 / 15.
double bumpIntegral(double t) {
  t = std::max(-1.0, std::min(1.0, t));
  const double t2 = t * t;
  return t * (1.0 - t2 * (2.0 / 3.0) + t2 * t2 * 0.2);
}

double bump(double t) {
  if (t <= -1.0 || t >= 1.0) {
    return 0.0;
  }
  const double s = 1.0 - t * t;
  return s * s;
}

/// std::min(a, b) and std::max(a, b) by value (the same results), for the vectorised loops.
HAIR_SIM_ALWAYS_INLINE double minOf(double a, double b) { return b < a ? b : a; }
HAIR_SIM_ALWAYS_INLINE double maxOf(double a, double b) { return a < b ? b : a; }

HAIR_SIM_ALWAYS_INLINE double smoothstep(double x) {
  x = maxOf(0.0, minOf(1.0, x));
  return x * x * (3.0 - 2.0 * x);
}

/// HairLook::rootFactor and tipFade with their parameters.
HAIR_SIM_ALWAYS_INLINE double rootFactorOf(double v, double root_darkening, double root_length) {
  return 1.0 - root_darkening * (1.0 - smoothstep(v / root_length));
}
HAIR_SIM_ALWAYS_INLINE double tipFadeOf(double v, double tip_fade_start) {
  // Before tip_fade_start the smoothstep's argument is clamped to 0: exactly 1 (no branch on the data).
  return 1.0 - smoothstep((v - tip_fade_start) / (1.0 - tip_fade_start));
}

HAIR_SIM_ALWAYS_INLINE float clampChannel(double value) {
  return static_cast<float>(maxOf(0.0, minOf(1.0, value)));
}

void checkRange(double value, double low, double high, bool high_inclusive, const char* name) {
  const bool ok = std::isfinite(value) && value >= low && (high_inclusive ? value <= high : value < high);
  if (!ok) {
    throw std::invalid_argument(std::string("HairLook::HairLook(...) : ") + name + " must be in [" +
                                std::to_string(low) + ", " + std::to_string(high) +
                                (high_inclusive ? "]" : ")") + ", got " + std::to_string(value));
  }
}

Vec3 unitDirection(const Vec3& direction, const char* name) {
  const double norm = direction.norm();
  if (!direction.allFinite() || !(norm > 1e-12)) {
    throw std::invalid_argument(std::string("HairLook::HairLook(...) : ") + name +
                                " must be a finite non-zero vector, got (" + std::to_string(direction.x()) +
                                ", " + std::to_string(direction.y()) + ", " + std::to_string(direction.z()) +
                                ")");
  }
  return direction / norm;
}

void checkMesh(const StripMesh& mesh, const char* where) {
  const std::size_t count =
      static_cast<std::size_t>(std::max(mesh.n_u, 0)) * static_cast<std::size_t>(std::max(mesh.n_v, 0));
  if (mesh.n_u < 2 || mesh.n_v < 2 || mesh.positions.size() != count) {
    throw std::invalid_argument(std::string(where) +
                                " : mesh must be at least 2 x 2 with n_u * n_v positions, got " +
                                std::to_string(mesh.n_u) + " x " + std::to_string(mesh.n_v) + " and " +
                                std::to_string(mesh.positions.size()) + " positions");
  }
}

/// sin of the angle whose cosine is `cosine` (|cosine| <= 1 up to rounding): sqrt(max(0, 1 - cosine^2)).
HAIR_SIM_ALWAYS_INLINE double sine(double cosine) { return std::sqrt(maxOf(0.0, 1.0 - cosine * cosine)); }

/// Vertices per chunk of HairLook::colour's vectorised loops.
constexpr int kChunk = 64;

/// The Kajiya-Kay specular term (see HairLook::specular) of m <= kChunk vertices from T.L, T.V and
/// sin(T, L), step by step over all of them (loops the compiler vectorises). Back-facing highlights are 0:
/// the power of 0 (no branch on the data). An integer exponent (the default 40) by repeated squaring: a few
/// multiplications, within a few ulp of std::pow, which took 9 % of hair_sim_node's time with hair_markers
/// subscribed (every vertex, every frame).
HAIR_SIM_ALWAYS_INLINE void specularTerms(const double* tl, const double* tv, const double* sin_l, int m,
                                          double exponent, double* out) {
  double power[kChunk];
  for (int k = 0; k < m; ++k) {
    const double raw = minOf(1.0, sin_l[k] * sine(tv[k]) - tl[k] * tv[k]);
    power[k] = raw > 0.0 ? raw : 0.0;
  }
  if (exponent <= 1024.0 && exponent == std::floor(exponent)) {
    for (int k = 0; k < m; ++k) out[k] = 1.0;
    for (unsigned n = static_cast<unsigned>(exponent); n != 0; n >>= 1) {
      if (n & 1u)
        for (int k = 0; k < m; ++k) out[k] *= power[k];
      for (int k = 0; k < m; ++k) power[k] *= power[k];
    }
    return;
  }
  for (int k = 0; k < m; ++k) out[k] = std::pow(power[k], exponent);
}

/// What HairLook::colour needs for the lighting of one vertex column.
struct ColumnLighting {
  const StripMesh* mesh;
  Rgba* colours;
  const HairLookParameters* look;
  Vec3 light, view;  ///< unit
  double base_r, base_g, base_b, base_a;
  bool pattern;
  int iu;
  double stripe_alpha, stripe_brightness;
};

/// One vertex column of HairLook::colour in chunks, each step of the lighting a loop over the chunk that the
/// compiler vectorises (HairLook.cpp: -O3, no errno, no trapping math): per vertex the same operations as
/// diffuse(), specular(), rootFactor() and tipFade().
HAIR_SIM_ALWAYS_INLINE void lightColumnBody(const ColumnLighting& in) {
  const Vec3* tangents = in.mesh->tangents.data();
  const float* v_param = in.mesh->v_param.data();
  const int n_u = in.mesh->n_u, n_v = in.mesh->n_v, iu = in.iu;
  const HairLookParameters& look = *in.look;
  const double ambient = look.ambient, strength = look.specular_strength;
  for (int iv0 = 0; iv0 < n_v; iv0 += kChunk) {
    const int m = std::min(kChunk, n_v - iv0);
    double tl[kChunk], tv[kChunk], v[kChunk], sin_l[kChunk], highlight[kChunk];
    float r[kChunk], g[kChunk], b[kChunk], a[kChunk];
    for (int k = 0; k < m; ++k) {
      const std::size_t index = static_cast<std::size_t>(iv0 + k) * n_u + iu;
      tl[k] = tangents[index].dot(in.light);
      tv[k] = tangents[index].dot(in.view);
      v[k] = v_param[index];
    }
    for (int k = 0; k < m; ++k) sin_l[k] = sine(tl[k]);
    specularTerms(tl, tv, sin_l, m, look.specular_exponent, highlight);
    for (int k = 0; k < m; ++k) {
      const double light = ambient + (1.0 - ambient) * sin_l[k];
      const double shade =
          light * in.stripe_brightness * rootFactorOf(v[k], look.root_darkening, look.root_length);
      const double h = strength * highlight[k];
      r[k] = clampChannel(in.base_r * shade + h);
      g[k] = clampChannel(in.base_g * shade + h);
      b[k] = clampChannel(in.base_b * shade + h);
    }
    if (in.pattern) {
      for (int k = 0; k < m; ++k)
        a[k] = clampChannel(in.base_a * in.stripe_alpha * tipFadeOf(v[k], look.tip_fade_start));
    } else {
      for (int k = 0; k < m; ++k) a[k] = clampChannel(in.base_a);
    }
    for (int k = 0; k < m; ++k)
      in.colours[static_cast<std::size_t>(iv0 + k) * n_u + iu] = Rgba{r[k], g[k], b[k], a[k]};
  }
}

void lightColumnBaseline(const ColumnLighting& in) { lightColumnBody(in); }

#if defined(HAIR_SIM_AVX2_DISPATCH)
__attribute__((target("avx2"))) void lightColumnAvx2(const ColumnLighting& in) { lightColumnBody(in); }

#endif

}  // namespace

HairLook::HairLook(const HairLookParameters& parameters) : parameters_(parameters) {
  light_ = unitDirection(parameters.light_direction, "light_direction");
  view_ = unitDirection(parameters.view_direction, "view_direction");
  if (parameters.strands_per_strip < 1 || parameters.strands_per_strip > 10000) {
    throw std::invalid_argument("HairLook::HairLook(...) : strands_per_strip must be in [1, 10000], got " +
                                std::to_string(parameters.strands_per_strip));
  }
  checkRange(parameters.stripe_contrast, 0.0, 1.0, true, "stripe_contrast");
  checkRange(parameters.tip_fade_start, 0.0, 1.0, false, "tip_fade_start");
  checkRange(parameters.root_darkening, 0.0, 1.0, true, "root_darkening");
  checkRange(parameters.root_length, 1e-9, 1.0, true, "root_length");
  checkRange(parameters.specular_strength, 0.0, 1e9, true, "specular_strength");
  checkRange(parameters.specular_exponent, 1.0, 1e6, true, "specular_exponent");
  checkRange(parameters.ambient, 0.0, 1.0, true, "ambient");
}

double HairLook::diffuse(const Vec3& tangent, const Vec3& light) { return sine(tangent.dot(light)); }

double HairLook::specular(const Vec3& tangent, const Vec3& light, const Vec3& view, double exponent) {
  const double tl = tangent.dot(light);
  const double tv = tangent.dot(view);
  const double sin_l = sine(tl);
  double term = 0.0;
  specularTerms(&tl, &tv, &sin_l, 1, exponent, &term);
  return term;
}

double HairLook::stripeProfile(double u, std::uint32_t strip_seed, double width) const {
  const int strands = parameters_.strands_per_strip;
  const double spacing = 1.0 / strands;
  const double half_width = kHalfWidth * spacing;
  const double phase = kPhase * (2.0 * unitHash(strip_seed, 0xFFFFFFFFU) - 1.0);
  width = std::max(0.0, width);
  const double a = u - 0.5 * width;
  const double b = u + 0.5 * width;
  // Only strands whose support [c - h, c + h] can meet [a, b] contribute (centres move by < 0.5 spacing).
  const int first = std::max(0, static_cast<int>(std::floor(a * strands - 1.0)));
  const int last = std::min(strands - 1, static_cast<int>(std::ceil(b * strands + 1.0)));
  double sum = 0.0;
  for (int k = first; k <= last; ++k) {
    const double jitter = kJitter * (2.0 * unitHash(strip_seed, static_cast<std::uint32_t>(k)) - 1.0);
    const double centre = (k + 0.5 + phase + jitter) * spacing;
    if (width > 0.0) {
      sum += half_width *
             (bumpIntegral((b - centre) / half_width) - bumpIntegral((a - centre) / half_width)) / width;
    } else {
      sum += bump((u - centre) / half_width);
    }
  }
  return std::max(0.0, std::min(1.0, sum));
}

double HairLook::tipFade(double v) const { return tipFadeOf(v, parameters_.tip_fade_start); }

double HairLook::rootFactor(double v) const {
  return rootFactorOf(v, parameters_.root_darkening, parameters_.root_length);
}

void HairLook::colorize(const StripMesh& mesh, const Rgba& base, std::uint32_t strip_seed,
                        std::vector<Rgba>& colours) const {
  colour(mesh, base, strip_seed, true, nullptr, colours);
}

void HairLook::stripeProfiles(const StripMesh& mesh, std::uint32_t strip_seed,
                              std::vector<double>& profiles) const {
  checkMesh(mesh, "HairLook::stripeProfiles(...)");
  if (mesh.u_param.size() < static_cast<std::size_t>(mesh.n_u))
    throw std::invalid_argument("HairLook::stripeProfiles(...) : u_param has " +
                                std::to_string(mesh.u_param.size()) + " entries, n_u is " +
                                std::to_string(mesh.n_u));
  profiles.resize(static_cast<std::size_t>(mesh.n_u));
  for (int iu = 0; iu < mesh.n_u; ++iu)
    profiles[static_cast<std::size_t>(iu)] = columnProfile(mesh, iu, strip_seed);
}

void HairLook::colorize(const StripMesh& mesh, const Rgba& base, const std::vector<double>& profiles,
                        std::vector<Rgba>& colours) const {
  if (profiles.size() != static_cast<std::size_t>(std::max(mesh.n_u, 0)))
    throw std::invalid_argument("HairLook::colorize(...) : " + std::to_string(profiles.size()) +
                                " stripe profiles for a mesh of " + std::to_string(mesh.n_u) + " columns");
  colour(mesh, base, 0U, true, profiles.data(), colours);
}

void HairLook::shade(const StripMesh& mesh, const Rgba& base, std::vector<Rgba>& colours) const {
  colour(mesh, base, 0U, false, nullptr, colours);
}

double HairLook::columnProfile(const StripMesh& mesh, int iu, std::uint32_t strip_seed) const {
  // The vertex spacing across as the box filter's width (a mip-mapped texture's footprint).
  return stripeProfile(mesh.u_param[static_cast<std::size_t>(iu)], strip_seed,
                       1.0 / static_cast<double>(mesh.n_u - 1));
}

void HairLook::colour(const StripMesh& mesh, const Rgba& base, std::uint32_t strip_seed, bool pattern,
                      const double* profiles, std::vector<Rgba>& colours) const {
  const char* where = pattern ? "HairLook::colorize(...)" : "HairLook::shade(...)";
  checkMesh(mesh, where);
  const std::size_t count = mesh.positions.size();
  if (mesh.tangents.size() != count || mesh.v_param.size() != count || mesh.u_param.size() != count) {
    throw std::invalid_argument(
        std::string(where) + " : tangents, v_param and u_param must have " + std::to_string(count) +
        " entries, got " + std::to_string(mesh.tangents.size()) + ", " + std::to_string(mesh.v_param.size()) +
        ", " + std::to_string(mesh.u_param.size()));
  }
  colours.resize(count);
  const double base_r = clampChannel(base.r);
  const double base_g = clampChannel(base.g);
  const double base_b = clampChannel(base.b);
  const double base_a = clampChannel(base.a);
  const double contrast = parameters_.stripe_contrast;
  void (*lightColumn)(const ColumnLighting&) = lightColumnBaseline;
#if defined(HAIR_SIM_AVX2_DISPATCH)
  if (cpuHasAvx2()) lightColumn = lightColumnAvx2;
#endif
  ColumnLighting column{&mesh,  colours.data(), &parameters_, light_, view_, base_r, base_g,
                        base_b, base_a,         pattern,      0,      1.0,   1.0};
  for (int iu = 0; iu < mesh.n_u; ++iu) {
    const double profile = !pattern              ? 1.0
                           : profiles != nullptr ? profiles[iu]
                                                 : columnProfile(mesh, iu, strip_seed);
    column.iu = iu;
    column.stripe_alpha = 1.0 - contrast * (1.0 - profile);
    column.stripe_brightness = 1.0 - 0.5 * contrast * (1.0 - profile);
    lightColumn(column);
  }
}

void HairLook::strandLines(const StripMesh& mesh, int strands, std::vector<Vec3>& points,
                           const std::vector<Rgba>* colours, std::vector<Rgba>* point_colours) {
  if (strands < 1) {
    throw std::invalid_argument("HairLook::strandLines(...) : strands must be >= 1, got " +
                                std::to_string(strands));
  }
  std::vector<double> u_values(static_cast<std::size_t>(strands));
  for (int k = 0; k < strands; ++k) {
    u_values[static_cast<std::size_t>(k)] = (k + 0.5) / strands;
  }
  strandLines(mesh, u_values, points, colours, point_colours);
}

void HairLook::strandLines(const StripMesh& mesh, const std::vector<double>& u_values,
                           std::vector<Vec3>& points, const std::vector<Rgba>* colours,
                           std::vector<Rgba>* point_colours) {
  checkMesh(mesh, "HairLook::strandLines(...)");
  if (colours != nullptr && colours->size() != mesh.positions.size()) {
    throw std::invalid_argument("HairLook::strandLines(...) : colours must have one entry per vertex (" +
                                std::to_string(mesh.positions.size()) + "), got " +
                                std::to_string(colours->size()));
  }
  for (double u : u_values) {
    if (!(u >= 0.0 && u <= 1.0)) {
      throw std::invalid_argument("HairLook::strandLines(...) : u values must be in [0, 1], got " +
                                  std::to_string(u));
    }
  }
  const bool with_colours = colours != nullptr && point_colours != nullptr;
  auto lerp_colour = [](const Rgba& a, const Rgba& b, float f) {
    return Rgba{a.r + f * (b.r - a.r), a.g + f * (b.g - a.g), a.b + f * (b.b - a.b), a.a + f * (b.a - a.a)};
  };
  for (double u : u_values) {
    const double x = u * (mesh.n_u - 1);
    const int i0 = std::min(static_cast<int>(x), mesh.n_u - 2);
    const double f = x - i0;
    auto point_at = [&mesh, i0, f](int iv) {
      const Vec3& a = mesh.positions[static_cast<std::size_t>(mesh.index(i0, iv))];
      const Vec3& b = mesh.positions[static_cast<std::size_t>(mesh.index(i0 + 1, iv))];
      return Vec3(a + f * (b - a));
    };
    auto colour_at = [&mesh, colours, i0, f, &lerp_colour](int iv) {
      return lerp_colour((*colours)[static_cast<std::size_t>(mesh.index(i0, iv))],
                         (*colours)[static_cast<std::size_t>(mesh.index(i0 + 1, iv))], static_cast<float>(f));
    };
    Vec3 start = point_at(0);
    for (int iv = 1; iv < mesh.n_v; ++iv) {
      const Vec3 end = point_at(iv);
      if ((end - start).squaredNorm() > 0.0) {
        points.push_back(start);
        points.push_back(end);
        if (with_colours) {
          point_colours->push_back(colour_at(iv - 1));
          point_colours->push_back(colour_at(iv));
        }
      }
      start = end;
    }
  }
}

}  // namespace hair_sim
