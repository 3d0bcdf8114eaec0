#include "hair_sim/core/geometry/Tessellator.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "../SimdDispatch.hpp"

// SSE2 (baseline on x86-64) kernels for the CachedBasis method and the frame normalisation; the portable
// scalar code below is used elsewhere, or everywhere with -DHAIR_SIM_NO_SIMD (both paths are tested).
#if defined(__SSE2__) && !defined(HAIR_SIM_NO_SIMD)
#define HAIR_SIM_SSE2 1
#include <emmintrin.h>
#include <xmmintrin.h>
// AVX2 kernels compiled for that target only and chosen at run time when the CPU has it (-DHAIR_SIM_NO_AVX2
// keeps the SSE2 kernels). Both give bit-identical results: same operations in the same order, no FMA.
#if defined(HAIR_SIM_AVX2_DISPATCH)
#define HAIR_SIM_AVX2 1
#define HAIR_SIM_AVX2_TARGET __attribute__((target("avx2")))
#include <immintrin.h>
#endif
#endif

#include "hair_sim/core/geometry/BSplineSurface.hpp"

namespace hair_sim {

namespace {

constexpr double kTinySquaredNorm = std::numeric_limits<double>::min();

/// Forward differences of a cubic (or lower degree) polynomial sampled at equal steps.
struct ForwardDifferences {
  Vec3 f;
  Vec3 d1;
  Vec3 d2;
  Vec3 d3;
  void step() {
    f += d1;
    d1 += d2;
    d2 += d3;
  }
};

/// Paper appendix, with its typos corrected: f(t) = a t^3 + b t^2 + c t + d sampled at t = 0, s, 2s, ...
/// f = d, Δf = a s^3 + b s^2 + c s, Δ²f = 6 a s^3 + 2 b s^2, Δ³f = 6 a s^3.
inline ForwardDifferences initForwardDifferences(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d,
                                                 double s) {
  const double s2 = s * s;
  const double s3 = s2 * s;
  ForwardDifferences fd;
  fd.f = d;
  fd.d1 = a * s3 + b * s2 + c * s;
  fd.d2 = a * (6.0 * s3) + b * (2.0 * s2);
  fd.d3 = a * (6.0 * s3);
  return fd;
}

/// Same for samples starting at t0 (t = t0, t0 + s, ...): the polynomial is first re-expanded in t0 + s m
/// and then differenced as above with unit step. Reduces to the appendix formulas when t0 = 0.
/// coefficients[k] multiplies t^k.
inline ForwardDifferences initForwardDifferencesFrom(const Vec3 coefficients[4], double t0, double s) {
  if (t0 == 0.0) {
    return initForwardDifferences(coefficients[3], coefficients[2], coefficients[1], coefficients[0], s);
  }
  const Vec3& c3 = coefficients[3];
  const Vec3& c2 = coefficients[2];
  const Vec3& c1 = coefficients[1];
  const Vec3& c0 = coefficients[0];
  const Vec3 a = c3;                                           // t^3 coefficient of the shifted polynomial
  const Vec3 b = 3.0 * t0 * c3 + c2;                           // t^2
  const Vec3 c = (3.0 * t0 * t0) * c3 + (2.0 * t0) * c2 + c1;  // t
  const Vec3 d = ((c3 * t0 + c2) * t0 + c1) * t0 + c0;         // value at t0
  return initForwardDifferences(a, b, c, d, s);
}

/// Unit tangent along dv and unit normal along du x dv, with deterministic fall-backs for degenerate
/// derivatives (tangent (0, 0, -1): hanging hair; normal: any unit vector perpendicular to the tangent).
void fallbackFrame(const Vec3& d_du, const Vec3& d_dv, Vec3& normal, Vec3& tangent) {
  const double t2 = d_dv.squaredNorm();
  tangent = t2 > kTinySquaredNorm ? Vec3(d_dv / std::sqrt(t2)) : Vec3(0.0, 0.0, -1.0);
  Vec3 n = d_du.cross(tangent);
  if (n.squaredNorm() <= kTinySquaredNorm) {
    const Vec3 axis = std::abs(tangent.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
    n = tangent.cross(axis);
  }
  normal = n.normalized();
}

static_assert(sizeof(Vec3) == 3 * sizeof(double), "Vec3 must be three packed doubles");

/// Range of |n|^2 and |t|^2 where every path (scalar, SSE2, AVX2) makes the unit frame as n * (1 / sqrt(n2)),
/// lane by lane, so that they give the same bits; outside it (degenerate or overflowing derivatives)
/// normalizeFrame's exact fall-back is taken. Every path tests min(n2, t2) >= kFastFrameMin and max(t2, n2)
/// <= kFastFrameMax in that operand order: min and max (std:: and SSE/AVX alike) return one operand when the
/// other is NaN, and with these orders a NaN in either fails one of the two tests everywhere (a NaN n2 comes
/// from inf - inf in du x dv when finite control points are ~1e154 apart).
constexpr double kFastFrameMin = 1e-30;
constexpr double kFastFrameMax = 1e30;

#if defined(HAIR_SIM_SSE2)
/// Two 3D vectors as x, y, z lane pairs (lane 0: first vertex, lane 1: second vertex).
struct Pair3 {
  __m128d x;
  __m128d y;
  __m128d z;
};

inline Pair3 operator+(const Pair3& a, const Pair3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Pair3 operator-(const Pair3& a, const Pair3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Pair3 operator*(__m128d s, const Pair3& a) { return {s * a.x, s * a.y, s * a.z}; }
inline __m128d dot(const Pair3& a, const Pair3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Pair3 cross(const Pair3& a, const Pair3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
/// x, y, z arrays `stride` doubles apart, two consecutive entries each.
inline Pair3 loadPair3(const double* x, std::size_t stride) {
  return {_mm_loadu_pd(x), _mm_loadu_pd(x + stride), _mm_loadu_pd(x + 2 * stride)};
}
inline void lane(const Pair3& value, int which, double out[3]) {
  if (which == 0) {
    out[0] = _mm_cvtsd_f64(value.x);
    out[1] = _mm_cvtsd_f64(value.y);
    out[2] = _mm_cvtsd_f64(value.z);
  } else {
    out[0] = _mm_cvtsd_f64(_mm_unpackhi_pd(value.x, value.x));
    out[1] = _mm_cvtsd_f64(_mm_unpackhi_pd(value.y, value.y));
    out[2] = _mm_cvtsd_f64(_mm_unpackhi_pd(value.z, value.z));
  }
}

/// 1 / sqrt(x) of both lanes, correctly rounded square root then division: the same bits as the scalar
/// 1.0 / std::sqrt(x). (A float estimate refined by two Newton steps, which this replaced, gave other bits
/// than the scalar code, a longer chain of dependent operations and a 1.04 x slower AVX2 tessellation.)
inline __m128d inverseSqrt(__m128d x) { return _mm_set1_pd(1.0) / _mm_sqrt_pd(x); }

/// Unit normal normalize(du x dv) and tangent normalize(dv) of two vertices.
/// Returns false (writing nothing) when a lane is outside the fast range.
inline bool unitFrames(const Pair3& du, const Pair3& dv, Pair3& normal, Pair3& tangent) {
  const Pair3 n = cross(du, dv);
  const __m128d n2 = dot(n, n);
  const __m128d t2 = dot(dv, dv);
  const __m128d in_range = _mm_and_pd(_mm_cmpge_pd(_mm_min_pd(n2, t2), _mm_set1_pd(kFastFrameMin)),
                                      _mm_cmple_pd(_mm_max_pd(t2, n2), _mm_set1_pd(kFastFrameMax)));
  if (_mm_movemask_pd(in_range) != 0x3) {
    return false;
  }
  normal = inverseSqrt(n2) * n;
  tangent = inverseSqrt(t2) * dv;
  return true;
}

/// Stores lane 0 at a and, when b is not null, lane 1 at b (three doubles each).
inline void storeLanes(const Pair3& value, double* a, double* b) {
  _mm_storeu_pd(a, _mm_unpacklo_pd(value.x, value.y));
  _mm_store_sd(a + 2, value.z);
  if (b != nullptr) {
    _mm_storeu_pd(b, _mm_unpackhi_pd(value.x, value.y));
    _mm_storeh_pd(b + 2, value.z);
  }
}
#endif

/// One vertex of normalizeFrames: in place, nd holds dS/du and td dS/dv on entry, the unit frame on exit.
/// Same arithmetic as the SIMD path lane by lane.
inline void normalizeFrame(double* nd, double* td) {
  const double ux = nd[0];
  const double uy = nd[1];
  const double uz = nd[2];
  const double vx = td[0];
  const double vy = td[1];
  const double vz = td[2];
  const double nx = uy * vz - uz * vy;
  const double ny = uz * vx - ux * vz;
  const double nz = ux * vy - uy * vx;
  const double n2 = nx * nx + ny * ny + nz * nz;
  const double t2 = vx * vx + vy * vy + vz * vz;
  if (std::min(n2, t2) >= kFastFrameMin && std::max(t2, n2) <= kFastFrameMax) {
    const double inverse_n = 1.0 / std::sqrt(n2);
    const double inverse_t = 1.0 / std::sqrt(t2);
    nd[0] = nx * inverse_n;
    nd[1] = ny * inverse_n;
    nd[2] = nz * inverse_n;
    td[0] = vx * inverse_t;
    td[1] = vy * inverse_t;
    td[2] = vz * inverse_t;
    return;
  }
  Vec3 normal;
  Vec3 tangent;
  const Vec3 d_du(ux, uy, uz);
  const Vec3 d_dv(vx, vy, vz);
  if (n2 > kTinySquaredNorm && t2 > kTinySquaredNorm) {
    normal = Vec3(nx, ny, nz) / std::sqrt(n2);
    tangent = d_dv / std::sqrt(t2);
  } else {
    fallbackFrame(d_du, d_dv, normal, tangent);
  }
  for (int k = 0; k < 3; ++k) {
    nd[k] = normal[k];
    td[k] = tangent[k];
  }
}

/// In place over a whole mesh: normals[i] holds dS/du and tangents[i] dS/dv on entry, the unit frame on
/// exit. SSE2: two vertices per step (their six doubles are transposed to x, y, z pairs and back).
void normalizeFrames(Vec3* normals, Vec3* tangents, std::size_t count) {
  double* nd = normals->data();
  double* td = tangents->data();
  std::size_t i = 0;
#if defined(HAIR_SIM_SSE2)
  for (; i + 2 <= count; i += 2, nd += 6, td += 6) {
    // [x0 y0] [z0 x1] [y1 z1] -> [x0 x1] [y0 y1] [z0 z1]
    const __m128d a0 = _mm_loadu_pd(nd);
    const __m128d a1 = _mm_loadu_pd(nd + 2);
    const __m128d a2 = _mm_loadu_pd(nd + 4);
    const __m128d b0 = _mm_loadu_pd(td);
    const __m128d b1 = _mm_loadu_pd(td + 2);
    const __m128d b2 = _mm_loadu_pd(td + 4);
    const Pair3 du{_mm_shuffle_pd(a0, a1, 0x2), _mm_shuffle_pd(a0, a2, 0x1), _mm_shuffle_pd(a1, a2, 0x2)};
    const Pair3 dv{_mm_shuffle_pd(b0, b1, 0x2), _mm_shuffle_pd(b0, b2, 0x1), _mm_shuffle_pd(b1, b2, 0x2)};
    Pair3 n;
    Pair3 t;
    if (!unitFrames(du, dv, n, t)) {
      normalizeFrame(nd, td);
      normalizeFrame(nd + 3, td + 3);
      continue;
    }
    // [x0 x1] [y0 y1] [z0 z1] -> [x0 y0] [z0 x1] [y1 z1]
    _mm_storeu_pd(nd, _mm_shuffle_pd(n.x, n.y, 0x0));
    _mm_storeu_pd(nd + 2, _mm_shuffle_pd(n.z, n.x, 0x2));
    _mm_storeu_pd(nd + 4, _mm_shuffle_pd(n.y, n.z, 0x3));
    _mm_storeu_pd(td, _mm_shuffle_pd(t.x, t.y, 0x0));
    _mm_storeu_pd(td + 2, _mm_shuffle_pd(t.z, t.x, 0x2));
    _mm_storeu_pd(td + 4, _mm_shuffle_pd(t.y, t.z, 0x3));
  }
#endif
  for (; i < count; ++i, nd += 3, td += 3) {
    normalizeFrame(nd, td);
  }
}

#if defined(HAIR_SIM_AVX2)
/// allFinite's AVX2 part: whether the first 4 * quads doubles are finite, four at a time, their exponent
/// bits compared as 64-bit integers.
HAIR_SIM_AVX2_TARGET bool quadsFinite(const double* values, std::size_t quads) {
  const __m256i exponent = _mm256_set1_epi64x(0x7FF0000000000000LL);
  __m256i all_ones = _mm256_setzero_si256();  // per lane: its exponent bits were all ones
  for (std::size_t q = 0; q < quads; ++q) {
    const __m256i bits = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(values + 4 * q));
    all_ones = _mm256_or_si256(all_ones, _mm256_cmpeq_epi64(_mm256_and_si256(bits, exponent), exponent));
  }
  return _mm256_testz_si256(all_ones, all_ones) != 0;
}
#endif

/// True when none of the `count` doubles is infinite or NaN (exponent bits all ones). Integer operations (no
/// floating-point exception flag is raised). With AVX2 four doubles at a time (quadsFinite); SSE2 has no
/// 64-bit integer comparison: two doubles at a time, their high 32-bit halves hold the exponent bits. The
/// rest one by one.
bool allFinite(const double* values, std::size_t count) {
  std::size_t i = 0;
#if defined(HAIR_SIM_AVX2)
  if (cpuHasAvx2()) {
    if (!quadsFinite(values, count / 4)) {
      return false;
    }
    i = count / 4 * 4;
  }
#endif
#if defined(HAIR_SIM_SSE2)
  const __m128i exponent = _mm_set_epi32(0x7FF00000, 0, 0x7FF00000, 0);
  __m128i all_ones = _mm_setzero_si128();  // per high half: its exponent bits were all ones
  for (; i + 2 <= count; i += 2) {
    const __m128i bits = _mm_loadu_si128(reinterpret_cast<const __m128i*>(values + i));
    all_ones = _mm_or_si128(all_ones, _mm_cmpeq_epi32(_mm_and_si128(bits, exponent), exponent));
  }
  // The low halves compare 0 == 0: only the high halves count.
  if (_mm_movemask_epi8(_mm_and_si128(all_ones, _mm_set_epi32(-1, 0, -1, 0))) != 0) {
    return false;
  }
#endif
  std::uint64_t non_finite = 0;
  for (; i < count; ++i) {
    std::uint64_t bits;
    std::memcpy(&bits, values + i, sizeof bits);
    non_finite |= static_cast<std::uint64_t>((bits & 0x7FF0000000000000ULL) == 0x7FF0000000000000ULL);
  }
  return non_finite == 0;
}

/// Sets the vertex count (resizing only changes capacity when the mesh grows) and u_param (a copy of
/// `u_param`, the whole grid's).
void prepareMesh(StripMesh& mesh, int n_u, int n_v, const std::vector<float>& u_param) {
  const std::size_t count = static_cast<std::size_t>(n_u) * static_cast<std::size_t>(n_v);
  mesh.n_u = n_u;
  mesh.n_v = n_v;
  mesh.positions.resize(count);
  mesh.normals.resize(count);
  mesh.tangents.resize(count);
  mesh.v_param.resize(count);
  mesh.u_param.resize(count);
  std::memcpy(mesh.u_param.data(), u_param.data(), count * sizeof(float));
}

void validateLevel(const LevelOfDetail& level, const char* where) {
  if (level.samples_across < 1 || level.samples_across > Tessellator::kMaxSamples) {
    throw std::invalid_argument(std::string(where) + " : samples_across must be in [1, " +
                                std::to_string(Tessellator::kMaxSamples) + "], got " +
                                std::to_string(level.samples_across));
  }
  if (level.samples_along < 1 || level.samples_along > Tessellator::kMaxSamples) {
    throw std::invalid_argument(std::string(where) + " : samples_along must be in [1, " +
                                std::to_string(Tessellator::kMaxSamples) + "], got " +
                                std::to_string(level.samples_along));
  }
}

/// "where :" or "where : strip N :" (strip >= 0), the start of the checks' messages.
std::string messagePrefix(const char* where, long long strip) {
  return std::string(where) + (strip >= 0 ? " : strip " + std::to_string(strip) + " :" : std::string(" :"));
}

/// Throws when the grid is too small; `strip` >= 0 is named in the message.
void validateShape(int columns, int rows, const char* where, long long strip = -1) {
  if (columns >= 2 && rows >= 4) {
    return;
  }
  const std::string prefix = messagePrefix(where, strip);
  if (columns < 2) {
    throw std::invalid_argument(prefix + " columns must be >= 2, got " + std::to_string(columns));
  }
  throw std::invalid_argument(prefix + " rows must be >= 4, got " + std::to_string(rows));
}

/// tessellate()'s checks of one strip; `strip` >= 0 is named in the message.
void checkStrip(const Vec3* control_points, int columns, int rows, double hair_length, const char* where,
                long long strip) {
  auto prefix = [where, strip] { return messagePrefix(where, strip); };  // only on the way to a throw
  if (control_points == nullptr) {
    throw std::invalid_argument(prefix() + " control_points is null");
  }
  validateShape(columns, rows, where, strip);
  if (!(hair_length > 0.0) || !std::isfinite(hair_length)) {
    throw std::invalid_argument(prefix() + " hair_length must be positive and finite, got " +
                                std::to_string(hair_length));
  }
  if (!allFinite(control_points->data(), 3 * static_cast<std::size_t>(columns) * rows)) {
    for (int i = 0; i < columns * rows; ++i) {
      if (control_points[i].allFinite()) {
        continue;
      }
      throw std::invalid_argument(prefix() + " control point " + std::to_string(i) + " (column " +
                                  std::to_string(i % columns) + ", row " + std::to_string(i / columns) +
                                  ") is not finite");
    }
  }
}

/// Extended control point (phantoms by reflection, see BSplineSurface) without range checks.
inline Vec3 extendedPoint(const Vec3* points, int columns, int rows, int column, int row) {
  auto in_row = [points, columns, column](int r) -> Vec3 {
    const Vec3* row_points = points + r * columns;
    if (column < 0) {
      return 2.0 * row_points[0] - row_points[1];
    }
    if (column >= columns) {
      return 2.0 * row_points[columns - 1] - row_points[columns - 2];
    }
    return row_points[column];
  };
  if (row < 0) {
    return 2.0 * in_row(0) - in_row(1);
  }
  if (row >= rows) {
    return 2.0 * in_row(rows - 1) - in_row(rows - 2);
  }
  return in_row(row);
}

/// Uniform B-spline basis of degree p at local t (and its derivative), values for the p + 1 span points.
void uniformBasis(int degree, double t, double value[4], double derivative[4]) {
  const double r = 1.0 - t;
  switch (degree) {
    case 1:
      value[0] = r;
      value[1] = t;
      derivative[0] = -1.0;
      derivative[1] = 1.0;
      break;
    case 2:
      value[0] = 0.5 * r * r;
      value[1] = 0.5 + t * r;
      value[2] = 0.5 * t * t;
      derivative[0] = -r;
      derivative[1] = 1.0 - 2.0 * t;
      derivative[2] = t;
      break;
    default:
      value[0] = r * r * r / 6.0;
      value[1] = (3.0 * t * t * t - 6.0 * t * t + 4.0) / 6.0;
      value[2] = (-3.0 * t * t * t + 3.0 * t * t + 3.0 * t + 1.0) / 6.0;
      value[3] = t * t * t / 6.0;
      derivative[0] = -0.5 * r * r;
      derivative[1] = 0.5 * (3.0 * t * t - 4.0 * t);
      derivative[2] = 0.5 * (-3.0 * t * t + 2.0 * t + 1.0);
      derivative[3] = 0.5 * t * t;
      break;
  }
}

/// The mesh's vertex arrays as plain pointers (the kernels' outputs).
struct MeshArrays {
  double* positions;
  double* normals;
  double* tangents;
  float* v_param;
};
inline MeshArrays meshArrays(StripMesh& mesh) {
  return {mesh.positions.data()->data(), mesh.normals.data()->data(), mesh.tangents.data()->data(),
          mesh.v_param.data()};
}

/// Clips a vertex column at the hair length inside the segment prev -> prev + step (walked length so far
/// `length` <= hair_length < length + |step|): the vertex moves back along the segment to the exact length,
/// its derivatives are interpolated likewise, and every later vertex of the column repeats it.
/// Shared by all methods so that they clip identically.
void clipColumn(StripMesh& mesh, int iu, int iv, const double* previous, const double* step, double segment,
                double length, double hair_length, const double* previous_du, const double* d_du,
                const double* previous_dv, const double* d_dv) {
  const double fraction = (hair_length - length) / segment;
  const Vec3 position(previous[0] + fraction * step[0], previous[1] + fraction * step[1],
                      previous[2] + fraction * step[2]);
  const Vec3 du(previous_du[0] + fraction * (d_du[0] - previous_du[0]),
                previous_du[1] + fraction * (d_du[1] - previous_du[1]),
                previous_du[2] + fraction * (d_du[2] - previous_du[2]));
  const Vec3 dv(previous_dv[0] + fraction * (d_dv[0] - previous_dv[0]),
                previous_dv[1] + fraction * (d_dv[1] - previous_dv[1]),
                previous_dv[2] + fraction * (d_dv[2] - previous_dv[2]));
  for (int r = iv; r < mesh.n_v; ++r) {
    const std::size_t index = static_cast<std::size_t>(r) * mesh.n_u + iu;
    mesh.positions[index] = position;
    mesh.normals[index] = du;  // raw derivatives until normalizeFrames()
    mesh.tangents[index] = dv;
    mesh.v_param[index] = 1.0f;
  }
}

#if defined(HAIR_SIM_SSE2)
/// CachedBasis kernels: raw derivatives of sample j of a vertex column from the column curve arrays (see
/// cachedColumnPairs; only needed where a column is clipped): coordinate q of sample j at
/// curve[q * stride + j * row_step].
void derivativesAt(const double* curve, const double* curve_dv, std::size_t stride, std::size_t row_step,
                   const double* weight, const double* derivative_weight, int width, int j, double du[3],
                   double dv[3]) {
  for (int k = 0; k < 3; ++k) {
    du[k] = 0.0;
    dv[k] = 0.0;
    for (int b = 0; b < width; ++b) {
      const std::size_t at =
          static_cast<std::size_t>(3 * b + k) * stride + static_cast<std::size_t>(j) * row_step;
      du[k] += derivative_weight[b] * curve[at];
      dv[k] += weight[b] * curve_dv[at];
    }
  }
}

/// After clipColumn (raw derivatives in rows iv..n_v-1 of column iu): unit frame of row iv copied below.
void normalizeColumnFrom(StripMesh& mesh, int iu, int iv) {
  const std::size_t index = static_cast<std::size_t>(iv) * mesh.n_u + iu;
  normalizeFrame(mesh.normals[index].data(), mesh.tangents[index].data());
  for (int r = iv + 1; r < mesh.n_v; ++r) {
    const std::size_t other = static_cast<std::size_t>(r) * mesh.n_u + iu;
    mesh.normals[other] = mesh.normals[index];
    mesh.tangents[other] = mesh.tangents[index];
  }
}

/// A CachedBasis column that reaches the hair length in its row j > 0 (walked `length` before it, `segment`
/// from `previous` by `step`): the raw derivatives of row j - 1 from the column curves (derivativesAt), then
/// clipColumn and the unit frames of the rows from j (normalizeColumnFrom).
void clipCachedColumn(StripMesh& mesh, int iu, int j, const double* curve, const double* curve_dv,
                      std::size_t stride, std::size_t row_step, const double* weight,
                      const double* derivative_weight, int width, const double* previous, const double* step,
                      double segment, double length, double hair_length, const double* current_du,
                      const double* current_dv) {
  double previous_du[3];
  double previous_dv[3];
  derivativesAt(curve, curve_dv, stride, row_step, weight, derivative_weight, width, j - 1, previous_du,
                previous_dv);
  clipColumn(mesh, iu, j, previous, step, segment, length, hair_length, previous_du, current_du, previous_dv,
             current_dv);
  normalizeColumnFrom(mesh, iu, j);
}

/// CachedBasis stage 1 (SSE2): the curves of all control columns and their d/dv, two v samples per step on a
/// window of K control rows, stored per coordinate q = column * 3 + k as arrays over the samples:
/// curve[q * stride + iv]. broadcast holds every control coordinate twice (row r at r * 6 * columns).
template <int K>
void columnCurvePairs(const double* broadcast, int columns, int pairs, const int* first, const double* weight,
                      const double* derivative, int stride, double* curve, double* curve_dv) {
  const int row = 6 * columns;
  for (int p = 0; p < pairs; ++p) {
    __m128d w[K];
    __m128d d[K];
#pragma GCC unroll 8
    for (int m = 0; m < K; ++m) {
      w[m] = _mm_loadu_pd(weight + 2 * (p * K + m));
      d[m] = _mm_loadu_pd(derivative + 2 * (p * K + m));
    }
    const double* base = broadcast + static_cast<std::size_t>(first[p]) * row;
    for (int q = 0; q < 3 * columns; ++q) {
      const double* b = base + 2 * q;
      __m128d x = _mm_loadu_pd(b);
      __m128d value = w[0] * x;
      __m128d slope = d[0] * x;
#pragma GCC unroll 8
      for (int m = 1; m < K; ++m) {
        x = _mm_loadu_pd(b + m * row);
        value += w[m] * x;
        slope += d[m] * x;
      }
      _mm_storeu_pd(curve + static_cast<std::size_t>(q) * stride + 2 * p, value);
      _mm_storeu_pd(curve_dv + static_cast<std::size_t>(q) * stride + 2 * p, slope);
    }
  }
}

/// CachedBasis stage 2 (SSE2), one vertex column, two v samples per step: combine the W column curves
/// across u (curve points at the first column's x array; y, z and the next columns follow `stride` doubles
/// apart), walk the length, clip, and store positions, unit frames and v_param.
template <int W>
void cachedColumnPairs(const double* curve, const double* curve_dv, int stride, const double* weight,
                       const double* derivative_weight, int iu, double hair_length, double inverse_length,
                       StripMesh& mesh) {
  const int n_u = mesh.n_u;
  const int n_v = mesh.n_v;
  const std::size_t s = static_cast<std::size_t>(stride);
  const auto [positions, normals, tangents, v_param] = meshArrays(mesh);
  __m128d w[W];
  __m128d dw[W];
#pragma GCC unroll 4
  for (int b = 0; b < W; ++b) {
    w[b] = _mm_set1_pd(weight[b]);
    dw[b] = _mm_set1_pd(derivative_weight[b]);
  }
  const __m128d zero = _mm_setzero_pd();
  Pair3 last{zero, zero, zero};
  double length = 0.0;
  for (int iv = 0; iv < n_v; iv += 2) {
    const bool second = iv + 1 < n_v;
    const Pair3 c0 = loadPair3(curve + iv, s);
    Pair3 p = w[0] * c0;
    Pair3 du = dw[0] * c0;
    Pair3 dv = w[0] * loadPair3(curve_dv + iv, s);
#pragma GCC unroll 4
    for (int b = 1; b < W; ++b) {
      const Pair3 c = loadPair3(curve + 3 * b * s + iv, s);
      p = p + w[b] * c;
      du = du + dw[b] * c;
      dv = dv + w[b] * loadPair3(curve_dv + 3 * b * s + iv, s);
    }
    const Pair3 previous =
        iv == 0 ? Pair3{_mm_unpacklo_pd(p.x, p.x), _mm_unpacklo_pd(p.y, p.y), _mm_unpacklo_pd(p.z, p.z)}
                : Pair3{_mm_shuffle_pd(last.x, p.x, 0x1), _mm_shuffle_pd(last.y, p.y, 0x1),
                        _mm_shuffle_pd(last.z, p.z, 0x1)};
    const Pair3 step = p - previous;
    const __m128d segment = _mm_sqrt_pd(dot(step, step));
    const double s0 = _mm_cvtsd_f64(segment);
    const double s1 = _mm_cvtsd_f64(_mm_unpackhi_pd(segment, segment));
    const double l0 = length + s0;
    const double l1 = l0 + s1;
    const std::size_t a = static_cast<std::size_t>(iv) * n_u + iu;
    const std::size_t b = a + n_u;
    if (l0 > hair_length || (second && l1 > hair_length)) {
      // The hair length is reached in this pair (once per column at most): finish in scalar code.
      double p0[3], du0[3], du1[3], dv0[3], dv1[3], step0[3], step1[3];
      lane(p, 0, p0);
      lane(du, 0, du0);
      lane(du, 1, du1);
      lane(dv, 0, dv0);
      lane(dv, 1, dv1);
      lane(step, 0, step0);
      lane(step, 1, step1);
      if (l0 > hair_length) {  // iv > 0 here: the root has l0 = 0
        double previous_p[3];
        lane(last, 1, previous_p);
        clipCachedColumn(mesh, iu, iv, curve, curve_dv, s, 1, weight, derivative_weight, W, previous_p, step0,
                         s0, length, hair_length, du0, dv0);
        return;
      }
      for (int k = 0; k < 3; ++k) {
        positions[3 * a + k] = p0[k];
        normals[3 * a + k] = du0[k];
        tangents[3 * a + k] = dv0[k];
      }
      normalizeFrame(normals + 3 * a, tangents + 3 * a);
      v_param[a] = static_cast<float>(l0 * inverse_length);
      clipColumn(mesh, iu, iv + 1, p0, step1, s1, l0, hair_length, du0, du1, dv0, dv1);
      normalizeColumnFrom(mesh, iu, iv + 1);
      return;
    }
    double* next_position = second ? positions + 3 * b : nullptr;
    double* next_normal = second ? normals + 3 * b : nullptr;
    double* next_tangent = second ? tangents + 3 * b : nullptr;
    storeLanes(p, positions + 3 * a, next_position);
    Pair3 n;
    Pair3 t;
    if (unitFrames(du, dv, n, t)) {
      storeLanes(n, normals + 3 * a, next_normal);
      storeLanes(t, tangents + 3 * a, next_tangent);
    } else {
      storeLanes(du, normals + 3 * a, next_normal);
      storeLanes(dv, tangents + 3 * a, next_tangent);
      normalizeFrame(normals + 3 * a, tangents + 3 * a);
      if (second) {
        normalizeFrame(next_normal, next_tangent);
      }
    }
    v_param[a] = static_cast<float>(l0 * inverse_length);
    if (second) {
      v_param[b] = static_cast<float>(l1 * inverse_length);
    }
    length = l1;
    last = p;
  }
}
#endif

#if defined(HAIR_SIM_AVX2)

/// The fewest vertex columns that go through cachedRowQuads together (fewer: cachedColumnQuads each). With
/// two, half the lanes idle and the rows kernel took 1.16 x the time of the columns kernel (2 x 5 strips at
/// level 1 x 4); with three 0.88 x, with four 0.75 x (4 x 5 strips at 1 x 4).
constexpr int kMinRowLanes = 3;

/// Strips in lanes (Tessellator's batch form, cachedStripRows): strips of two control columns at up to 3
/// samples across (2-4 vertex columns).
constexpr int kMaxLaneSamplesAcross = 3;

/// Four 3D vectors as x, y, z lane quads (lane l: sample iv + l).
struct Quad3 {
  __m256d x;
  __m256d y;
  __m256d z;
};

HAIR_SIM_AVX2_TARGET inline Quad3 loadQuad3(const double* x, std::size_t stride) {
  return {_mm256_loadu_pd(x), _mm256_loadu_pd(x + stride), _mm256_loadu_pd(x + 2 * stride)};
}
HAIR_SIM_AVX2_TARGET inline Quad3 scaled(__m256d s, const Quad3& a) { return {s * a.x, s * a.y, s * a.z}; }
HAIR_SIM_AVX2_TARGET inline Quad3 plus(const Quad3& a, const Quad3& b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
HAIR_SIM_AVX2_TARGET inline __m256d dot4(const Quad3& a, const Quad3& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}

/// Lane quad version of unitFrames (same arithmetic).
HAIR_SIM_AVX2_TARGET inline bool unitFrames4(const Quad3& du, const Quad3& dv, Quad3& normal,
                                             Quad3& tangent) {
  const Quad3 n{du.y * dv.z - du.z * dv.y, du.z * dv.x - du.x * dv.z, du.x * dv.y - du.y * dv.x};
  const __m256d n2 = dot4(n, n);
  const __m256d t2 = dot4(dv, dv);
  const __m256d in_range =
      _mm256_and_pd(_mm256_cmp_pd(_mm256_min_pd(n2, t2), _mm256_set1_pd(kFastFrameMin), _CMP_GE_OQ),
                    _mm256_cmp_pd(_mm256_max_pd(t2, n2), _mm256_set1_pd(kFastFrameMax), _CMP_LE_OQ));
  if (_mm256_movemask_pd(in_range) != 0xF) {
    return false;
  }
  const __m256d one = _mm256_set1_pd(1.0);
  const __m256d rn = one / _mm256_sqrt_pd(n2);
  const __m256d rt = one / _mm256_sqrt_pd(t2);
  normal = scaled(rn, n);
  tangent = scaled(rt, dv);
  return true;
}

/// Stores lane l < count at first + l * vertex_stride (three doubles each).
HAIR_SIM_AVX2_TARGET inline void storeQuadLanes(const Quad3& value, double* first, std::size_t vertex_stride,
                                                int count) {
  const __m256d even = _mm256_unpacklo_pd(value.x, value.y);  // x0 y0 | x2 y2
  const __m256d odd = _mm256_unpackhi_pd(value.x, value.y);   // x1 y1 | x3 y3
  const __m128d z_low = _mm256_castpd256_pd128(value.z);
  _mm_storeu_pd(first, _mm256_castpd256_pd128(even));
  _mm_store_sd(first + 2, z_low);
  if (count > 1) {
    double* out = first + vertex_stride;
    _mm_storeu_pd(out, _mm256_castpd256_pd128(odd));
    _mm_storeh_pd(out + 2, z_low);
  }
  if (count > 2) {
    const __m128d z_high = _mm256_extractf128_pd(value.z, 1);
    double* out = first + 2 * vertex_stride;
    _mm_storeu_pd(out, _mm256_extractf128_pd(even, 1));
    _mm_store_sd(out + 2, z_high);
    if (count > 3) {
      out += vertex_stride;
      _mm_storeu_pd(out, _mm256_extractf128_pd(odd, 1));
      _mm_storeh_pd(out + 2, z_high);
    }
  }
}

/// Stores float lane l < count at out + l * stride.
HAIR_SIM_AVX2_TARGET inline void storeFloatLanes(__m128 value, float* out, std::size_t stride, int count) {
  _mm_store_ss(out, value);
  if (count > 1) {
    _mm_store_ss(out + stride, _mm_movehdup_ps(value));
  }
  if (count > 2) {
    const __m128 high = _mm_movehl_ps(value, value);
    _mm_store_ss(out + 2 * stride, high);
    if (count > 3) {
      _mm_store_ss(out + 3 * stride, _mm_movehdup_ps(high));
    }
  }
}

/// stripRows' record of the rows where a lane's walk crosses the hair length, one array of lanes per
/// value (lane l of value q at [q][l]; recordCrossing): the row before's vertex (3),
/// the step to this row's (3), this row's raw derivatives d/du and d/dv (3 + 3), the row before's (3 + 3, as
/// derivativesAt computes them), the walked length before the step and the step's length.
enum ClipValue {
  kClipLast = 0,
  kClipStep = 3,
  kClipDu = 6,
  kClipDv = 9,
  kClipPreviousDu = 12,
  kClipPreviousDv = 15,
  kClipLength = 18,
  kClipSegment = 19,
  kClipValues = 20
};

/// The lanes of bits `over` as a mask (all bits set per lane).
HAIR_SIM_AVX2_TARGET inline __m256d laneMask(int over) {
  const __m256i lane_bit = _mm256_set_epi64x(8, 4, 2, 1);
  return _mm256_castsi256_pd(
      _mm256_cmpeq_epi64(_mm256_and_si256(_mm256_set1_epi64x(over), lane_bit), lane_bit));
}

/// Lanes of `mask` of value into at[0..3], the other lanes keeping theirs, or every lane where `first` (the
/// record holds nothing yet): by a blend, as AVX2's masked store is slow on some CPUs (microcoded on AMD's).
HAIR_SIM_AVX2_TARGET inline void storeMaskedLanes(double* at, __m256d mask, __m256d value, bool first) {
  _mm256_storeu_pd(at, first ? value : _mm256_blendv_pd(_mm256_loadu_pd(at), value, mask));
}

HAIR_SIM_AVX2_TARGET inline void storeMaskedQuad3(double (*at)[4], __m256d mask, const Quad3& value,
                                                  bool first) {
  storeMaskedLanes(at[0], mask, value.x, first);
  storeMaskedLanes(at[1], mask, value.y, first);
  storeMaskedLanes(at[2], mask, value.z, first);
}

/// Records the lanes of bits `over` (ClipValue) in `record`, by blends. `first`: the record holds no lane
/// yet, so every lane is written; the others are overwritten as they cross, and clipLanes discards what it
/// computes for lanes that never do.
HAIR_SIM_AVX2_TARGET inline void recordCrossing(double (*record)[4], int over, bool first, const Quad3& last,
                                                const Quad3& step, const Quad3& du, const Quad3& dv,
                                                const Quad3& previous_du, const Quad3& previous_dv,
                                                __m256d length, __m256d segment) {
  const __m256d mask = laneMask(over);
  storeMaskedQuad3(record + kClipLast, mask, last, first);
  storeMaskedQuad3(record + kClipStep, mask, step, first);
  storeMaskedQuad3(record + kClipDu, mask, du, first);
  storeMaskedQuad3(record + kClipDv, mask, dv, first);
  storeMaskedQuad3(record + kClipPreviousDu, mask, previous_du, first);
  storeMaskedQuad3(record + kClipPreviousDv, mask, previous_dv, first);
  storeMaskedLanes(record[kClipLength], mask, length, first);
  storeMaskedLanes(record[kClipSegment], mask, segment, first);
}

/// Lanes of `mask`: from + fraction (to - from), clipColumn's interpolation; the other lanes: fill.
HAIR_SIM_AVX2_TARGET inline __m256d interpolatedLanes(__m256d fill, __m256d from, __m256d to,
                                                      __m256d fraction, __m256d mask) {
  return _mm256_blendv_pd(fill, from + fraction * (to - from), mask);
}

/// clipColumn and normalizeColumnFrom for vertex column `column` of meshes[l], l in the bits of `crossed`
/// (clipColumn's arithmetic in lanes; the frame by unitFrames4, or normalizeFrame where a lane is out of its
/// range, as normalizeFrame alone would give it), from their record (ClipValue): the vertex moves back along
/// the step to the hair length, the raw derivatives are interpolated from the row before's, and every row of
/// the column from the crossing row down repeats the vertex, its unit frame and v = 1.
HAIR_SIM_AVX2_TARGET inline __attribute__((always_inline)) void clipLanes(const double (*record)[4],
                                                                          int crossed,
                                                                          const int* crossing_row,
                                                                          __m256d hair_length,
                                                                          StripMesh* meshes, int column) {
  const __m256d crossing = laneMask(crossed);
  const __m256d fraction =
      (hair_length - _mm256_loadu_pd(record[kClipLength])) / _mm256_loadu_pd(record[kClipSegment]);
  const Quad3 last = loadQuad3(record[kClipLast], 4);
  const Quad3 step = loadQuad3(record[kClipStep], 4);
  const Quad3 du = loadQuad3(record[kClipDu], 4);
  const Quad3 dv = loadQuad3(record[kClipDv], 4);
  const Quad3 previous_du = loadQuad3(record[kClipPreviousDu], 4);
  const Quad3 previous_dv = loadQuad3(record[kClipPreviousDv], 4);
  const Quad3 position{last.x + fraction * step.x, last.y + fraction * step.y, last.z + fraction * step.z};
  // The lanes not crossing get a unit frame (their record is another lane's or stale, and their results are
  // discarded), so that unitFrames4 judges only the others.
  const __m256d zero = _mm256_setzero_pd();
  const __m256d one = _mm256_set1_pd(1.0);
  const Quad3 clip_du{interpolatedLanes(one, previous_du.x, du.x, fraction, crossing),
                      interpolatedLanes(zero, previous_du.y, du.y, fraction, crossing),
                      interpolatedLanes(zero, previous_du.z, du.z, fraction, crossing)};
  const Quad3 clip_dv{interpolatedLanes(zero, previous_dv.x, dv.x, fraction, crossing),
                      interpolatedLanes(one, previous_dv.y, dv.y, fraction, crossing),
                      interpolatedLanes(zero, previous_dv.z, dv.z, fraction, crossing)};
  Quad3 n;
  Quad3 t;
  const bool unit = unitFrames4(clip_du, clip_dv, n, t);
  alignas(32) double lanes[9][4];
  const Quad3* values[3] = {&position, unit ? &n : &clip_du, unit ? &t : &clip_dv};
  for (int v = 0; v < 3; ++v) {
    _mm256_store_pd(lanes[3 * v], values[v]->x);
    _mm256_store_pd(lanes[3 * v + 1], values[v]->y);
    _mm256_store_pd(lanes[3 * v + 2], values[v]->z);
  }
  for (int l = 0; l < 4; ++l) {
    if (!(crossed & (1 << l))) {
      continue;
    }
    StripMesh& m = meshes[l];
    const std::size_t n_u = static_cast<std::size_t>(m.n_u);
    Vec3 normal(lanes[3][l], lanes[4][l], lanes[5][l]);
    Vec3 tangent(lanes[6][l], lanes[7][l], lanes[8][l]);
    if (!unit) {
      normalizeFrame(normal.data(), tangent.data());
    }
    const Vec3 vertex(lanes[0][l], lanes[1][l], lanes[2][l]);
    for (std::size_t at = static_cast<std::size_t>(crossing_row[l]) * n_u + static_cast<std::size_t>(column);
         at < m.positions.size(); at += n_u) {
      m.positions[at] = vertex;
      m.normals[at] = normal;
      m.tangents[at] = tangent;
      m.v_param[at] = 1.0f;
    }
  }
}

/// CachedBasis stage 1 (AVX2): as columnCurvePairs with four samples per step, reading the control points
/// directly (broadcast loads).
template <int K>
HAIR_SIM_AVX2_TARGET void columnCurveQuads(const double* control, int columns, int quads, const int* first,
                                           const double* weight, const double* derivative, int stride,
                                           double* curve, double* curve_dv) {
  const int row = 3 * columns;
  for (int g = 0; g < quads; ++g) {
    __m256d w[K];
    __m256d d[K];
#pragma GCC unroll 8
    for (int m = 0; m < K; ++m) {
      w[m] = _mm256_loadu_pd(weight + 4 * (g * K + m));
      d[m] = _mm256_loadu_pd(derivative + 4 * (g * K + m));
    }
    const double* base = control + static_cast<std::size_t>(first[g]) * row;
    for (int q = 0; q < row; ++q) {
      const double* b = base + q;
      __m256d x = _mm256_broadcast_sd(b);
      __m256d value = w[0] * x;
      __m256d slope = d[0] * x;
#pragma GCC unroll 8
      for (int m = 1; m < K; ++m) {
        x = _mm256_broadcast_sd(b + m * row);
        value += w[m] * x;
        slope += d[m] * x;
      }
      _mm256_storeu_pd(curve + static_cast<std::size_t>(q) * stride + 4 * g, value);
      _mm256_storeu_pd(curve_dv + static_cast<std::size_t>(q) * stride + 4 * g, slope);
    }
  }
}

/// CachedBasis stage 2 (AVX2): as cachedColumnPairs with four v samples per step.
template <int W>
HAIR_SIM_AVX2_TARGET void cachedColumnQuads(const double* curve, const double* curve_dv, int stride,
                                            const double* weight, const double* derivative_weight, int iu,
                                            double hair_length, double inverse_length, StripMesh& mesh) {
  const int n_u = mesh.n_u;
  const int n_v = mesh.n_v;
  const std::size_t s = static_cast<std::size_t>(stride);
  const std::size_t vertex_stride = 3 * static_cast<std::size_t>(n_u);
  const auto [positions, normals, tangents, v_param] = meshArrays(mesh);
  __m256d w[W];
  __m256d dw[W];
#pragma GCC unroll 4
  for (int b = 0; b < W; ++b) {
    w[b] = _mm256_set1_pd(weight[b]);
    dw[b] = _mm256_set1_pd(derivative_weight[b]);
  }
  __m256d last_x = _mm256_setzero_pd();
  __m256d last_y = _mm256_setzero_pd();
  __m256d last_z = _mm256_setzero_pd();
  double length = 0.0;
  for (int iv = 0; iv < n_v; iv += 4) {
    const int count = std::min(4, n_v - iv);
    const Quad3 c0 = loadQuad3(curve + iv, s);
    Quad3 p = scaled(w[0], c0);
    Quad3 du = scaled(dw[0], c0);
    Quad3 dv = scaled(w[0], loadQuad3(curve_dv + iv, s));
#pragma GCC unroll 4
    for (int b = 1; b < W; ++b) {
      const Quad3 c = loadQuad3(curve + 3 * b * s + iv, s);
      p = plus(p, scaled(w[b], c));
      du = plus(du, scaled(dw[b], c));
      dv = plus(dv, scaled(w[b], loadQuad3(curve_dv + 3 * b * s + iv, s)));
    }
    if (iv == 0) {  // the root has no previous sample: repeat it (zero first segment)
      last_x = _mm256_permute4x64_pd(p.x, 0);
      last_y = _mm256_permute4x64_pd(p.y, 0);
      last_z = _mm256_permute4x64_pd(p.z, 0);
    }
    // previous = [last lane 3, p lane 0, p lane 1, p lane 2]
    const __m256d sx = p.x - _mm256_shuffle_pd(_mm256_permute2f128_pd(last_x, p.x, 0x21), p.x, 0x5);
    const __m256d sy = p.y - _mm256_shuffle_pd(_mm256_permute2f128_pd(last_y, p.y, 0x21), p.y, 0x5);
    const __m256d sz = p.z - _mm256_shuffle_pd(_mm256_permute2f128_pd(last_z, p.z, 0x21), p.z, 0x5);
    const __m256d segments = _mm256_sqrt_pd(sx * sx + sy * sy + sz * sz);
    // The walked length after each lane, added in lane order (as the SSE2 and scalar kernels do), then one
    // comparison of the real lanes (< count) with the hair length: the first lane over it is where the
    // column is clipped, as lane by lane (a NaN walk, from coordinates that overflow, never crosses).
    const __m128d low = _mm256_castpd256_pd128(segments);
    const __m128d high = _mm256_extractf128_pd(segments, 1);
    const double walked0 = length + _mm_cvtsd_f64(low);
    const double walked1 = walked0 + _mm_cvtsd_f64(_mm_unpackhi_pd(low, low));
    const double walked2 = walked1 + _mm_cvtsd_f64(high);
    const double walked3 = walked2 + _mm_cvtsd_f64(_mm_unpackhi_pd(high, high));
    const __m256d walked_quad = _mm256_set_pd(walked3, walked2, walked1, walked0);
    const int over = _mm256_movemask_pd(_mm256_cmp_pd(walked_quad, _mm256_set1_pd(hair_length), _CMP_GT_OQ)) &
                     ((1 << count) - 1);
    const std::size_t a = static_cast<std::size_t>(iv) * n_u + iu;
    if (over == 0) {
      storeQuadLanes(p, positions + 3 * a, vertex_stride, count);
      Quad3 n;
      Quad3 t;
      if (unitFrames4(du, dv, n, t)) {
        storeQuadLanes(n, normals + 3 * a, vertex_stride, count);
        storeQuadLanes(t, tangents + 3 * a, vertex_stride, count);
      } else {
        storeQuadLanes(du, normals + 3 * a, vertex_stride, count);
        storeQuadLanes(dv, tangents + 3 * a, vertex_stride, count);
        for (int l = 0; l < count; ++l) {
          const std::size_t offset = 3 * a + static_cast<std::size_t>(l) * vertex_stride;
          normalizeFrame(normals + offset, tangents + offset);
        }
      }
      const __m128 parameter = _mm256_cvtpd_ps(walked_quad * _mm256_set1_pd(inverse_length));
      storeFloatLanes(parameter, v_param + a, static_cast<std::size_t>(n_u), count);
      length = count == 4 ? walked3 : (count == 3 ? walked2 : (count == 2 ? walked1 : walked0));
      last_x = p.x;
      last_y = p.y;
      last_z = p.z;
      continue;
    }
    // The hair length is reached in this quad (once per column at most): finish in scalar code.
    const double walked[4] = {walked0, walked1, walked2, walked3};
    const int crossing = __builtin_ctz(static_cast<unsigned>(over));
    alignas(32) double segment[4];
    _mm256_store_pd(segment, segments);
    alignas(32) double lanes[9][4];
    _mm256_store_pd(lanes[0], p.x);
    _mm256_store_pd(lanes[1], p.y);
    _mm256_store_pd(lanes[2], p.z);
    _mm256_store_pd(lanes[3], du.x);
    _mm256_store_pd(lanes[4], du.y);
    _mm256_store_pd(lanes[5], du.z);
    _mm256_store_pd(lanes[6], dv.x);
    _mm256_store_pd(lanes[7], dv.y);
    _mm256_store_pd(lanes[8], dv.z);
    for (int l = 0; l < crossing; ++l) {
      const std::size_t index = a + static_cast<std::size_t>(l) * n_u;
      for (int k = 0; k < 3; ++k) {
        positions[3 * index + k] = lanes[k][l];
        normals[3 * index + k] = lanes[3 + k][l];
        tangents[3 * index + k] = lanes[6 + k][l];
      }
      normalizeFrame(normals + 3 * index, tangents + 3 * index);
      v_param[index] = static_cast<float>(walked[l] * inverse_length);
    }
    const int j = iv + crossing;  // j > 0: the root has a zero segment
    double previous[3], current_du[3], current_dv[3], step[3];
    const double* before = positions + 3 * (a + static_cast<std::size_t>(crossing) * n_u) - vertex_stride;
    for (int k = 0; k < 3; ++k) {
      previous[k] = before[k];
      current_du[k] = lanes[3 + k][crossing];
      current_dv[k] = lanes[6 + k][crossing];
      step[k] = lanes[k][crossing] - previous[k];
    }
    clipCachedColumn(mesh, iu, j, curve, curve_dv, s, 1, weight, derivative_weight, W, previous, step,
                     segment[crossing], crossing == 0 ? length : walked[crossing - 1], hair_length,
                     current_du, current_dv);
    return;
  }
}

/// CachedBasis stage 2 (AVX2), vertex columns in lanes: `count` (kMinRowLanes-4) consecutive vertex columns
/// from iu0 whose across samples share their first control column, one row (v sample) per step. Each lane
/// walks its own column's length with a vector add: the same sums in the same order as cachedColumnQuads,
/// without the prefix sum across lanes, and a row's vertices are contiguous in the mesh. A lane whose walk
/// crosses the hair length has its column finished by clipColumn after the last row (over the rows the loop
/// went on writing).
template <int W>
HAIR_SIM_AVX2_TARGET void cachedRowQuads(const double* curve, const double* curve_dv, int stride,
                                         const double* const* weights, const double* const* derivatives,
                                         int iu0, int count, double hair_length, double inverse_length,
                                         StripMesh& mesh) {
  const int n_u = mesh.n_u;
  const int n_v = mesh.n_v;
  const std::size_t s = static_cast<std::size_t>(stride);
  const auto [positions, normals, tangents, v_param] = meshArrays(mesh);
  __m256d w[W];
  __m256d dw[W];
#pragma GCC unroll 4
  for (int b = 0; b < W; ++b) {
    alignas(32) double lane_w[4];
    alignas(32) double lane_dw[4];
    for (int l = 0; l < 4; ++l) {  // an idle lane repeats the last column
      lane_w[l] = weights[std::min(l, count - 1)][b];
      lane_dw[l] = derivatives[std::min(l, count - 1)][b];
    }
    w[b] = _mm256_load_pd(lane_w);
    dw[b] = _mm256_load_pd(lane_dw);
  }
  const __m256d limit = _mm256_set1_pd(hair_length);
  const __m256d inverse = _mm256_set1_pd(inverse_length);
  const int real = (1 << count) - 1;
  int crossed = 0;
  // Per crossed lane: the row, the walk before it, the segment, the previous vertex, the step and the raw
  // derivatives.
  int crossing_row[4] = {0, 0, 0, 0};
  double crossing_length[4];
  double crossing_segment[4];
  double crossing_previous[4][3];
  double crossing_step[4][3];
  double crossing_du[4][3];
  double crossing_dv[4][3];
  __m256d length = _mm256_setzero_pd();
  Quad3 last{};
  for (int iv = 0; iv < n_v; ++iv) {
    Quad3 p;
    Quad3 du;
    Quad3 dv;
    {
      const double* c = curve + iv;
      const double* d = curve_dv + iv;
      const __m256d cx = _mm256_broadcast_sd(c);
      const __m256d cy = _mm256_broadcast_sd(c + s);
      const __m256d cz = _mm256_broadcast_sd(c + 2 * s);
      p = {w[0] * cx, w[0] * cy, w[0] * cz};
      du = {dw[0] * cx, dw[0] * cy, dw[0] * cz};
      dv = {w[0] * _mm256_broadcast_sd(d), w[0] * _mm256_broadcast_sd(d + s),
            w[0] * _mm256_broadcast_sd(d + 2 * s)};
    }
#pragma GCC unroll 4
    for (int b = 1; b < W; ++b) {
      const double* c = curve + 3 * b * s + iv;
      const double* d = curve_dv + 3 * b * s + iv;
      const __m256d cx = _mm256_broadcast_sd(c);
      const __m256d cy = _mm256_broadcast_sd(c + s);
      const __m256d cz = _mm256_broadcast_sd(c + 2 * s);
      p = plus(p, Quad3{w[b] * cx, w[b] * cy, w[b] * cz});
      du = plus(du, Quad3{dw[b] * cx, dw[b] * cy, dw[b] * cz});
      dv = plus(dv, Quad3{w[b] * _mm256_broadcast_sd(d), w[b] * _mm256_broadcast_sd(d + s),
                          w[b] * _mm256_broadcast_sd(d + 2 * s)});
    }
    if (iv == 0) {  // the root has no previous sample: a zero first segment
      last = p;
    }
    const Quad3 step{p.x - last.x, p.y - last.y, p.z - last.z};
    const __m256d segment = _mm256_sqrt_pd(dot4(step, step));
    const __m256d walked = length + segment;
    const int over = _mm256_movemask_pd(_mm256_cmp_pd(walked, limit, _CMP_GT_OQ)) & real & ~crossed;
    if (over != 0) {  // rare: once per column at most
      for (int l = 0; l < count; ++l) {
        if (!(over & (1 << l))) {
          continue;
        }
        crossing_row[l] = iv;
        crossing_segment[l] = segment[l];
        crossing_length[l] = length[l];
        const double previous[3] = {last.x[l], last.y[l], last.z[l]};
        const double lane_step[3] = {step.x[l], step.y[l], step.z[l]};
        const double lane_du[3] = {du.x[l], du.y[l], du.z[l]};
        const double lane_dv[3] = {dv.x[l], dv.y[l], dv.z[l]};
        for (int k = 0; k < 3; ++k) {
          crossing_previous[l][k] = previous[k];
          crossing_step[l][k] = lane_step[k];
          crossing_du[l][k] = lane_du[k];
          crossing_dv[l][k] = lane_dv[k];
        }
      }
      crossed |= over;
    }
    const std::size_t a = static_cast<std::size_t>(iv) * n_u + iu0;
    storeQuadLanes(p, positions + 3 * a, 3, count);
    Quad3 n;
    Quad3 t;
    if (unitFrames4(du, dv, n, t)) {
      storeQuadLanes(n, normals + 3 * a, 3, count);
      storeQuadLanes(t, tangents + 3 * a, 3, count);
    } else {
      storeQuadLanes(du, normals + 3 * a, 3, count);
      storeQuadLanes(dv, tangents + 3 * a, 3, count);
      for (int l = 0; l < count; ++l) {
        normalizeFrame(normals + 3 * (a + l), tangents + 3 * (a + l));
      }
    }
    storeFloatLanes(_mm256_cvtpd_ps(walked * inverse), v_param + a, 1, count);
    length = walked;
    last = p;
  }
  for (int l = 0; l < count; ++l) {
    if (!(crossed & (1 << l))) {
      continue;
    }
    // crossing_row[l] > 0: the root has a zero segment.
    clipCachedColumn(mesh, iu0 + l, crossing_row[l], curve, curve_dv, s, 1, weights[l], derivatives[l], W,
                     crossing_previous[l], crossing_step[l], crossing_segment[l], crossing_length[l],
                     hair_length, crossing_du[l], crossing_dv[l]);
  }
}

/// Stores lane l at out[l] + offset (three doubles each).
HAIR_SIM_AVX2_TARGET inline void storeStripLanes(const Quad3& value, double* const out[4],
                                                 std::size_t offset) {
  const __m256d even = _mm256_unpacklo_pd(value.x, value.y);  // x0 y0 | x2 y2
  const __m256d odd = _mm256_unpackhi_pd(value.x, value.y);   // x1 y1 | x3 y3
  const __m128d z_low = _mm256_castpd256_pd128(value.z);
  const __m128d z_high = _mm256_extractf128_pd(value.z, 1);
  _mm_storeu_pd(out[0] + offset, _mm256_castpd256_pd128(even));
  _mm_store_sd(out[0] + offset + 2, z_low);
  _mm_storeu_pd(out[1] + offset, _mm256_castpd256_pd128(odd));
  _mm_storeh_pd(out[1] + offset + 2, z_low);
  _mm_storeu_pd(out[2] + offset, _mm256_extractf128_pd(even, 1));
  _mm_store_sd(out[2] + offset + 2, z_high);
  _mm_storeu_pd(out[3] + offset, _mm256_extractf128_pd(odd, 1));
  _mm_storeh_pd(out[3] + offset + 2, z_high);
}

/// out[4 * i + l] = strip[l][i] for i < count (four strips' coordinates into lanes): 4 x 4 transposes.
HAIR_SIM_AVX2_TARGET void interleaveStrips(const double* const strip[4], std::size_t count, double* out) {
  std::size_t i = 0;
  for (; i + 4 <= count; i += 4) {
    const __m256d a = _mm256_loadu_pd(strip[0] + i);
    const __m256d b = _mm256_loadu_pd(strip[1] + i);
    const __m256d c = _mm256_loadu_pd(strip[2] + i);
    const __m256d d = _mm256_loadu_pd(strip[3] + i);
    const __m256d ab_even = _mm256_unpacklo_pd(a, b);  // a0 b0 | a2 b2
    const __m256d ab_odd = _mm256_unpackhi_pd(a, b);   // a1 b1 | a3 b3
    const __m256d cd_even = _mm256_unpacklo_pd(c, d);
    const __m256d cd_odd = _mm256_unpackhi_pd(c, d);
    _mm256_storeu_pd(out + 4 * i, _mm256_permute2f128_pd(ab_even, cd_even, 0x20));
    _mm256_storeu_pd(out + 4 * i + 4, _mm256_permute2f128_pd(ab_odd, cd_odd, 0x20));
    _mm256_storeu_pd(out + 4 * i + 8, _mm256_permute2f128_pd(ab_even, cd_even, 0x31));
    _mm256_storeu_pd(out + 4 * i + 12, _mm256_permute2f128_pd(ab_odd, cd_odd, 0x31));
  }
  for (; i < count; ++i) {
    for (int l = 0; l < 4; ++l) {
      out[4 * i + static_cast<std::size_t>(l)] = strip[l][i];
    }
  }
}

/// The control rows of four strips of two control columns in lanes (Tessellator::tessellateCachedBasisLanes):
/// coordinate q (column * 3 + k) of control row r of strip l at control[4 * (6 r + q) + l].
constexpr int kLaneControlRow = 4 * 6;

/// CachedBasis (AVX2), strips in lanes: four strips of two control columns and one row count, one strip per
/// lane (control: kLaneControlRow), every row step all NU (2-4) vertex columns. Two control columns make one
/// linear span across, whose derivative weights (`derivative`) are the same at every vertex column. The row's
/// column curves are computed in the step from the quads' window of K control rows (no curve arrays: that
/// work fills the ports the square roots and divisions leave idle), then shared by the NU columns, whose
/// length walks are independent chains; no lane idles (cachedRowQuads, with one strip's three columns in
/// lanes, leaves one of four). Each lane computes what columnCurveQuads, then cachedRowQuads or
/// cachedColumnQuads compute for its strip's column, in the same order. Lanes that cross their hair length
/// are recorded as they cross (recordCrossing) and their columns finished after the row loop, four lanes at
/// once, with clipColumn's arithmetic (clipLanes).
template <int K, int NU>
HAIR_SIM_AVX2_TARGET void stripRows(const double* control, const int* first, const double* along_weight,
                                    const double* along_derivative, const double* const* weights,
                                    const double* derivative, const double* hair_length,
                                    const double* inverse_length, StripMesh* meshes) {
  constexpr int W = 2;
  const int n_v = meshes[0].n_v;
  double* positions[4];
  double* normals[4];
  double* tangents[4];
  float* v_param[4];
  for (int l = 0; l < 4; ++l) {
    const MeshArrays arrays = meshArrays(meshes[l]);
    positions[l] = arrays.positions;
    normals[l] = arrays.normals;
    tangents[l] = arrays.tangents;
    v_param[l] = arrays.v_param;
  }
  __m256d w[NU][W];
  for (int u = 0; u < NU; ++u) {
    for (int b = 0; b < W; ++b) {
      w[u][b] = _mm256_set1_pd(weights[u][b]);
    }
  }
  const __m256d dw[W] = {_mm256_set1_pd(derivative[0]), _mm256_set1_pd(derivative[1])};
  const __m256d limit = _mm256_loadu_pd(hair_length);
  const __m256d inverse = _mm256_loadu_pd(inverse_length);
  int crossed[NU] = {};
  int crossing_row[NU][4] = {};
  __m256d length[NU];
  Quad3 last[NU];
  double record[NU][kClipValues][4];  // (written whole at a column's first crossing: recordCrossing)
  __m256d last_curve[6] = {};         // the row before's (for a clip)
  __m256d last_slope[6] = {};
  const int all_crossed = 0xF;
  for (int u = 0; u < NU; ++u) {
    length[u] = _mm256_setzero_pd();
    last[u] = Quad3{};
  }
  for (int iv = 0; iv < n_v; ++iv) {
    // The two control columns' curves at this sample (stage 1 of the other kernels).
    __m256d curve[6];
    __m256d slope[6];
    {
      const int g = iv / 4;
      const double* aw = along_weight + 4 * g * K + iv % 4;
      const double* ad = along_derivative + 4 * g * K + iv % 4;
      const double* base = control + static_cast<std::size_t>(kLaneControlRow) * first[g];
#pragma GCC unroll 6
      for (int q = 0; q < 6; ++q) {
        __m256d x = _mm256_loadu_pd(base + 4 * q);
        __m256d value = _mm256_set1_pd(aw[0]) * x;
        __m256d rate = _mm256_set1_pd(ad[0]) * x;
#pragma GCC unroll 8
        for (int m = 1; m < K; ++m) {
          x = _mm256_loadu_pd(base + 4 * q + kLaneControlRow * m);
          value += _mm256_set1_pd(aw[4 * m]) * x;
          rate += _mm256_set1_pd(ad[4 * m]) * x;
        }
        curve[q] = value;
        slope[q] = rate;
      }
    }
    const Quad3 c[W] = {{curve[0], curve[1], curve[2]}, {curve[3], curve[4], curve[5]}};
    const Quad3 d[W] = {{slope[0], slope[1], slope[2]}, {slope[3], slope[4], slope[5]}};
    // d/du: one linear span across, the same derivative weights at every vertex column, so once per row.
    const Quad3 du = plus(scaled(dw[0], c[0]), scaled(dw[1], c[1]));
#pragma GCC unroll 8
    for (int u = 0; u < NU; ++u) {
      Quad3 p = scaled(w[u][0], c[0]);
      Quad3 dv = scaled(w[u][0], d[0]);
#pragma GCC unroll 4
      for (int b = 1; b < W; ++b) {
        p = plus(p, scaled(w[u][b], c[b]));
        dv = plus(dv, scaled(w[u][b], d[b]));
      }
      if (iv == 0) {  // the root has no previous sample: a zero first segment
        last[u] = p;
      }
      const Quad3 step{p.x - last[u].x, p.y - last[u].y, p.z - last[u].z};
      const __m256d segment = _mm256_sqrt_pd(dot4(step, step));
      const __m256d walked = length[u] + segment;
      const int over = _mm256_movemask_pd(_mm256_cmp_pd(walked, limit, _CMP_GT_OQ)) & ~crossed[u];
      if (over != 0) {  // once per lane and column at most: the hair length ends in this row's segment
        // The row before's derivatives as derivativesAt computes them (iv > 0: the root's step is zero).
        const __m256d zero = _mm256_setzero_pd();
        const Quad3 previous_du{zero + dw[0] * last_curve[0] + dw[1] * last_curve[3],
                                zero + dw[0] * last_curve[1] + dw[1] * last_curve[4],
                                zero + dw[0] * last_curve[2] + dw[1] * last_curve[5]};
        const Quad3 previous_dv{zero + w[u][0] * last_slope[0] + w[u][1] * last_slope[3],
                                zero + w[u][0] * last_slope[1] + w[u][1] * last_slope[4],
                                zero + w[u][0] * last_slope[2] + w[u][1] * last_slope[5]};
        recordCrossing(record[u], over, crossed[u] == 0, last[u], step, du, dv, previous_du, previous_dv,
                       length[u], segment);
        for (int l = 0; l < 4; ++l) {
          if (over & (1 << l)) {
            crossing_row[u][l] = iv;
          }
        }
        crossed[u] |= over;
      }
      const std::size_t a = static_cast<std::size_t>(iv) * NU + u;
      storeStripLanes(p, positions, 3 * a);
      Quad3 n;
      Quad3 t;
      if (unitFrames4(du, dv, n, t)) {
        storeStripLanes(n, normals, 3 * a);
        storeStripLanes(t, tangents, 3 * a);
      } else {
        storeStripLanes(du, normals, 3 * a);
        storeStripLanes(dv, tangents, 3 * a);
        for (int l = 0; l < 4; ++l) {
          normalizeFrame(normals[l] + 3 * a, tangents[l] + 3 * a);
        }
      }
      const __m128 parameter = _mm256_cvtpd_ps(walked * inverse);
      const __m128 high = _mm_movehl_ps(parameter, parameter);
      _mm_store_ss(v_param[0] + a, parameter);
      _mm_store_ss(v_param[1] + a, _mm_movehdup_ps(parameter));
      _mm_store_ss(v_param[2] + a, high);
      _mm_store_ss(v_param[3] + a, _mm_movehdup_ps(high));
      length[u] = walked;
      last[u] = p;
    }
    for (int q = 0; q < 6; ++q) {
      last_curve[q] = curve[q];
      last_slope[q] = slope[q];
    }
    // Every column of every lane clipped: the rows below only repeat the clipped vertices.
    bool done = true;
    for (int u = 0; u < NU; ++u) {
      done = done && crossed[u] == all_crossed;
    }
    if (done) {
      break;
    }
  }
  for (int u = 0; u < NU; ++u) {
    if (crossed[u] != 0) {
      clipLanes(record[u], crossed[u], crossing_row[u], limit, meshes, u);
    }
  }
}
#endif

#if !defined(HAIR_SIM_SSE2)
/// CachedBasis stage 1: every control column's curve and its d/dv at every v sample (4 weights on 4
/// consecutive control rows, each row `stride` contiguous doubles; STRIDE > 0 fixes it at compile time).
template <int STRIDE, typename Table>
void columnCurves(const double* control, const Table& along, int n_v, int stride, double* curve,
                  double* curve_dv) {
  const int row_stride = STRIDE > 0 ? STRIDE : stride;
  for (int iv = 0; iv < n_v; ++iv) {
    const auto& sample = along.samples[static_cast<std::size_t>(iv)];
    const double* r0 = control + static_cast<std::size_t>(sample.first) * row_stride;
    const double* r1 = r0 + row_stride;
    const double* r2 = r1 + row_stride;
    const double* r3 = r2 + row_stride;
    const double w0 = sample.weight[0];
    const double w1 = sample.weight[1];
    const double w2 = sample.weight[2];
    const double w3 = sample.weight[3];
    const double d0 = sample.derivative[0];
    const double d1 = sample.derivative[1];
    const double d2 = sample.derivative[2];
    const double d3 = sample.derivative[3];
    double* out = curve + static_cast<std::size_t>(iv) * row_stride;
    double* out_dv = curve_dv + static_cast<std::size_t>(iv) * row_stride;
    for (int q = 0; q < row_stride; ++q) {
      out[q] = w0 * r0[q] + w1 * r1[q] + w2 * r2[q] + w3 * r3[q];
      out_dv[q] = d0 * r0[q] + d1 * r1[q] + d2 * r2[q] + d3 * r3[q];
    }
  }
}

/// CachedBasis, one vertex column: combine the W column curves across u with the sample's weights, walk the
/// length along v and clip. Raw derivatives go to normals (d/du) and tangents (d/dv).
template <int W>
void cachedColumn(const double* curve, const double* curve_dv, int row_stride, const double* weight,
                  const double* derivative_weight, int iu, double hair_length, double inverse_length,
                  StripMesh& mesh) {
  double w[W];
  double dw[W];
  for (int b = 0; b < W; ++b) {
    w[b] = weight[b];
    dw[b] = derivative_weight[b];
  }
  const int n_u = mesh.n_u;
  const int n_v = mesh.n_v;
  const auto [positions, derivatives_u, derivatives_v, v_param] = meshArrays(mesh);  // raw derivatives
  double length = 0.0;
  double previous[3] = {0.0, 0.0, 0.0};
  for (int iv = 0; iv < n_v; ++iv) {
    const double* c = curve + static_cast<std::size_t>(iv) * row_stride;
    const double* d = curve_dv + static_cast<std::size_t>(iv) * row_stride;
    double p[3];
    double du[3];
    double dv[3];
    for (int k = 0; k < 3; ++k) {
      p[k] = w[0] * c[k];
      du[k] = dw[0] * c[k];
      dv[k] = w[0] * d[k];
      for (int b = 1; b < W; ++b) {
        p[k] += w[b] * c[3 * b + k];
        du[k] += dw[b] * c[3 * b + k];
        dv[k] += w[b] * d[3 * b + k];
      }
    }
    const std::size_t index = static_cast<std::size_t>(iv) * n_u + iu;
    double* out = positions + 3 * index;
    if (iv > 0) {
      const double step[3] = {p[0] - previous[0], p[1] - previous[1], p[2] - previous[2]};
      const double segment = std::sqrt(step[0] * step[0] + step[1] * step[1] + step[2] * step[2]);
      if (length + segment > hair_length) {
        clipColumn(mesh, iu, iv, previous, step, segment, length, hair_length,
                   derivatives_u + 3 * (index - n_u), du, derivatives_v + 3 * (index - n_u), dv);
        return;
      }
      length += segment;
    }
    double* out_du = derivatives_u + 3 * index;
    double* out_dv = derivatives_v + 3 * index;
    for (int k = 0; k < 3; ++k) {
      out[k] = p[k];
      out_du[k] = du[k];
      out_dv[k] = dv[k];
      previous[k] = p[k];
    }
    v_param[index] = static_cast<float>(length * inverse_length);
  }
}
#endif

}  // namespace

std::int64_t StripMesh::triangleCount() const {
  if (n_u < 2 || n_v < 2) {
    return 0;
  }
  return 2 * static_cast<std::int64_t>(n_u - 1) * static_cast<std::int64_t>(n_v - 1);
}

Tessellator::Tessellator(const LevelOfDetail& level_of_detail, TessellationMethod method)
    : level_of_detail_(level_of_detail), method_(method) {
  validateLevel(level_of_detail, "Tessellator::Tessellator(...)");
}

void Tessellator::setLevelOfDetail(const LevelOfDetail& level_of_detail) {
  validateLevel(level_of_detail, "Tessellator::setLevelOfDetail(...)");
  if (level_of_detail.samples_across != level_of_detail_.samples_across) {
    across_tables_.clear();
  }
  if (level_of_detail.samples_along != level_of_detail_.samples_along) {
    along_tables_.clear();
  }
  level_of_detail_ = level_of_detail;
}

int Tessellator::verticesAcross(int columns, const LevelOfDetail& level_of_detail) {
  return (columns - 1) * level_of_detail.samples_across + 1;
}

int Tessellator::verticesAlong(int rows, const LevelOfDetail& level_of_detail) {
  return (rows - 1) * level_of_detail.samples_along + 1;
}

std::int64_t Tessellator::triangleCount(const StripShape& shape, const LevelOfDetail& level_of_detail) {
  validateShape(shape.columns, shape.rows, "Tessellator::triangleCount(...)");
  validateLevel(level_of_detail, "Tessellator::triangleCount(...)");
  return 2 * static_cast<std::int64_t>(shape.columns - 1) * level_of_detail.samples_across *
         static_cast<std::int64_t>(shape.rows - 1) * level_of_detail.samples_along;
}

std::int64_t Tessellator::triangleCount(const std::vector<StripShape>& hairstyle,
                                        const LevelOfDetail& level_of_detail) {
  std::int64_t total = 0;
  for (std::size_t i = 0; i < hairstyle.size(); ++i) {
    validateShape(hairstyle[i].columns, hairstyle[i].rows, "Tessellator::triangleCount(...)",
                  static_cast<int>(i));
    total += triangleCount(hairstyle[i], level_of_detail);
  }
  return total;
}

LevelOfDetail Tessellator::ladderLevel(int k) {
  if (k < 0) {
    throw std::invalid_argument("Tessellator::ladderLevel(...) : k must be >= 0, got " + std::to_string(k));
  }
  LevelOfDetail level;
  level.samples_along = k + 1;
  level.samples_across = std::max(1, level.samples_along / 2);
  return level;
}

LevelOfDetail Tessellator::selectLevelOfDetail(const std::vector<StripShape>& hairstyle,
                                               std::int64_t max_triangles) {
  if (max_triangles <= 0) {
    throw std::invalid_argument("Tessellator::selectLevelOfDetail(...) : max_triangles must be > 0, got " +
                                std::to_string(max_triangles));
  }
  const std::int64_t minimum = triangleCount(hairstyle, ladderLevel(0));
  if (minimum > max_triangles) {
    throw std::invalid_argument("Tessellator::selectLevelOfDetail(...) : max_triangles " +
                                std::to_string(max_triangles) + " is below the minimum level's " +
                                std::to_string(minimum) + " triangles");
  }
  int k = 0;
  while (k + 2 <= kMaxSelectableSamplesAlong &&
         triangleCount(hairstyle, ladderLevel(k + 1)) <= max_triangles) {
    ++k;
  }
  return ladderLevel(k);
}

void Tessellator::appendTriangles(const StripMesh& mesh, std::uint32_t first_vertex, bool both_windings,
                                  std::vector<std::uint32_t>& indices) {
  const int n_u = mesh.n_u;
  for (int iv = 0; iv + 1 < mesh.n_v; ++iv) {
    for (int iu = 0; iu + 1 < n_u; ++iu) {
      const std::uint32_t a = first_vertex + static_cast<std::uint32_t>(iv * n_u + iu);
      const std::uint32_t b = a + 1;
      const std::uint32_t c = a + static_cast<std::uint32_t>(n_u);
      const std::uint32_t d = c + 1;
      indices.insert(indices.end(), {a, b, c});
      if (both_windings) {
        indices.insert(indices.end(), {a, c, b});
      }
      indices.insert(indices.end(), {b, d, c});
      if (both_windings) {
        indices.insert(indices.end(), {b, c, d});
      }
    }
  }
}

const char* Tessellator::instructionSet() {
#if defined(HAIR_SIM_AVX2)
  if (cpuHasAvx2()) {
    return "AVX2";
  }
#endif
#if defined(HAIR_SIM_SSE2)
  return "SSE2";
#else
  return "scalar";
#endif
}

const char* Tessellator::methodName(TessellationMethod method) {
  switch (method) {
    case TessellationMethod::ForwardDifferencing:
      return "ForwardDifferencing";
    case TessellationMethod::DeBoor:
      return "DeBoor";
    case TessellationMethod::CachedBasis:
      return "CachedBasis";
  }
  return "Unknown";
}

void Tessellator::buildTable(int control_count, int degree, int samples_per_span, BasisTable& table) {
  const int spans = control_count - 1;
  const int count = spans * samples_per_span + 1;
  const int width = degree + 1;
  const double scale = static_cast<double>(spans);  // d/du = d/dx * (control_count - 1)
  table.control_count = control_count;
  table.width = width;
  table.samples.assign(static_cast<std::size_t>(count), BasisSample{});
  for (int k = 0; k < count; ++k) {
    BasisSample& sample = table.samples[static_cast<std::size_t>(k)];
    int extended_first = 0;
    if (degree == 2) {
      // Pieces centred on the control points: piece = round(k / samples), local s = x - piece + 1/2.
      sample.piece = std::min((2 * k + samples_per_span) / (2 * samples_per_span), control_count - 1);
      sample.s = static_cast<double>(2 * (k - sample.piece * samples_per_span) + samples_per_span) /
                 static_cast<double>(2 * samples_per_span);
      extended_first = sample.piece - 1;
    } else {
      sample.piece = std::min(k / samples_per_span, spans - 1);
      sample.s =
          static_cast<double>(k - sample.piece * samples_per_span) / static_cast<double>(samples_per_span);
      extended_first = degree == 3 ? sample.piece - 1 : sample.piece;
    }
    double value[4] = {0.0, 0.0, 0.0, 0.0};
    double derivative[4] = {0.0, 0.0, 0.0, 0.0};
    uniformBasis(degree, sample.s, value, derivative);
    // Fold the phantom weights onto real points: P[-1] = 2 P[0] - P[1], P[n] = 2 P[n-1] - P[n-2].
    sample.first = std::max(0, std::min(extended_first, control_count - width));
    auto add = [&sample](int real, double w, double dw) {
      const int slot = real - sample.first;
      sample.weight[slot] += w;
      sample.derivative[slot] += dw;
    };
    for (int b = 0; b < width; ++b) {
      const int index = extended_first + b;
      const double w = value[b];
      const double dw = derivative[b] * scale;
      if (index < 0) {
        add(0, 2.0 * w, 2.0 * dw);
        add(1, -w, -dw);
      } else if (index >= control_count) {
        add(control_count - 1, 2.0 * w, 2.0 * dw);
        add(control_count - 2, -w, -dw);
      } else {
        add(index, w, dw);
      }
    }
  }
}

const std::vector<float>& Tessellator::uParam(int n_u, int n_v) {
  if (n_u == u_param_n_u_ && n_v == u_param_n_v_) {
    return u_param_;
  }
  u_param_.resize(static_cast<std::size_t>(n_u) * static_cast<std::size_t>(n_v));
  const float inverse = 1.0f / static_cast<float>(n_u - 1);
  for (int iv = 0; iv < n_v; ++iv) {
    for (int iu = 0; iu < n_u; ++iu) {
      u_param_[static_cast<std::size_t>(iv) * n_u + iu] =
          iu == n_u - 1 ? 1.0f : static_cast<float>(iu) * inverse;
    }
  }
  u_param_n_u_ = n_u;
  u_param_n_v_ = n_v;
  return u_param_;
}

const Tessellator::BasisTable& Tessellator::acrossTable(int columns) {
  for (const BasisTable& table : across_tables_) {
    if (table.control_count == columns) {
      return table;
    }
  }
  across_tables_.emplace_back();
  buildTable(columns, BSplineSurface::degreeAcross(columns), level_of_detail_.samples_across,
             across_tables_.back());
  return across_tables_.back();
}

const Tessellator::BasisTable& Tessellator::alongTable(int rows) {
  for (const BasisTable& table : along_tables_) {
    if (table.control_count == rows) {
      return table;
    }
  }
  along_tables_.emplace_back();
  buildTable(rows, BSplineSurface::kDegreeAlong, level_of_detail_.samples_along, along_tables_.back());
  BasisTable& table = along_tables_.back();
  buildLaneGroups(table, 2, table.pairs);
  buildLaneGroups(table, 4, table.quads);
  return along_tables_.back();
}

void Tessellator::buildLaneGroups(const BasisTable& table, int lanes, LaneGroups& groups) {
  const int count = static_cast<int>(table.samples.size());
  const int group_count = (count + lanes - 1) / lanes;
  auto sample = [&table, count](int i) -> const BasisSample& {
    return table.samples[static_cast<std::size_t>(std::min(i, count - 1))];
  };
  int spread = 0;  // firsts are non-decreasing along the samples
  for (int g = 0; g < group_count; ++g) {
    spread = std::max(spread, sample(lanes * g + lanes - 1).first - sample(lanes * g).first);
  }
  const int window = std::min(table.width + spread, table.control_count);
  groups.lanes = lanes;
  groups.window = window;
  groups.first.assign(static_cast<std::size_t>(group_count), 0);
  groups.weight.assign(static_cast<std::size_t>(group_count * window * lanes), 0.0);
  groups.derivative.assign(static_cast<std::size_t>(group_count * window * lanes), 0.0);
  for (int g = 0; g < group_count; ++g) {
    const int first = std::max(0, std::min(sample(lanes * g).first, table.control_count - window));
    groups.first[static_cast<std::size_t>(g)] = first;
    for (int l = 0; l < lanes; ++l) {
      const BasisSample& s = sample(lanes * g + l);
      for (int j = 0; j < table.width; ++j) {
        const std::size_t slot = static_cast<std::size_t>(lanes * (g * window + s.first + j - first) + l);
        groups.weight[slot] += s.weight[j];
        groups.derivative[slot] += s.derivative[j];
      }
    }
  }
}

void Tessellator::emitVertex(ColumnWalk& walk, int iu, int iv, const Vec3& position, const Vec3& step,
                             const Vec3& d_du, const Vec3& d_dv, double hair_length, double inverse_length,
                             StripMesh& mesh) {
  const std::size_t index = static_cast<std::size_t>(iv) * mesh.n_u + iu;
  if (iv == 0) {
    walk.length = 0.0;
    walk.clipped = false;
  } else {
    const double segment = step.norm();
    if (walk.length + segment > hair_length) {
      clipColumn(mesh, iu, iv, walk.position.data(), step.data(), segment, walk.length, hair_length,
                 walk.d_du.data(), d_du.data(), walk.d_dv.data(), d_dv.data());
      walk.clipped = true;
      return;
    }
    walk.length += segment;
  }
  walk.position = position;
  walk.d_du = d_du;
  walk.d_dv = d_dv;
  mesh.positions[index] = position;
  mesh.normals[index] = d_du;  // raw derivatives until normalizeFrames()
  mesh.tangents[index] = d_dv;
  mesh.v_param[index] = static_cast<float>(walk.length * inverse_length);
}

void Tessellator::tessellate(const std::vector<Vec3>& control_points, int columns, int rows,
                             double hair_length, StripMesh& mesh) {
  validateShape(columns, rows, "Tessellator::tessellate(...)");
  if (control_points.size() != static_cast<std::size_t>(columns) * static_cast<std::size_t>(rows)) {
    throw std::invalid_argument("Tessellator::tessellate(...) : control_points has " +
                                std::to_string(control_points.size()) +
                                " points, columns * rows = " + std::to_string(columns * rows));
  }
  tessellate(control_points.data(), columns, rows, hair_length, mesh);
}

void Tessellator::tessellate(const Vec3* control_points, int columns, int rows, double hair_length,
                             StripMesh& mesh) {
  checkStrip(control_points, columns, rows, hair_length, "Tessellator::tessellate(...)", -1);
  tessellateChecked(control_points, columns, rows, hair_length, mesh);
}

void Tessellator::tessellate(const StripInput* strips, std::size_t count, StripMesh* meshes,
                             std::size_t first_index) {
  const char* where = "Tessellator::tessellate(...)";
  if (count == 0) {
    return;
  }
  if (strips == nullptr || meshes == nullptr) {
    throw std::invalid_argument(std::string(where) + " : " + (strips == nullptr ? "strips" : "meshes") +
                                " is null with count " + std::to_string(count));
  }
  for (std::size_t i = 0; i < count; ++i) {
    const StripInput& strip = strips[i];
    checkStrip(strip.control_points, strip.columns, strip.rows, strip.hair_length, where,
               static_cast<long long>(first_index + i));
  }
  std::size_t i = 0;
#if defined(HAIR_SIM_AVX2)
  if (method_ == TessellationMethod::CachedBasis && cpuHasAvx2()) {
    while (i + 4 <= count) {
      const StripInput* four = strips + i;
      bool same = level_of_detail_.samples_across <= kMaxLaneSamplesAcross;
      for (int l = 0; l < 4; ++l) {
        same = same && four[l].columns == 2 && four[l].rows == four[0].rows;
      }
      if (!same) {
        tessellateChecked(four->control_points, four->columns, four->rows, four->hair_length, meshes[i]);
        ++i;
        continue;
      }
      const int n_u = verticesAcross(four->columns, level_of_detail_);
      const int n_v = verticesAlong(four->rows, level_of_detail_);
      const std::vector<float>& u_param = uParam(n_u, n_v);
      for (int l = 0; l < 4; ++l) {
        prepareMesh(meshes[i + static_cast<std::size_t>(l)], n_u, n_v, u_param);
      }
      tessellateCachedBasisLanes(four, meshes + i);
      i += 4;
    }
  }
#endif
  for (; i < count; ++i) {
    tessellateChecked(strips[i].control_points, strips[i].columns, strips[i].rows, strips[i].hair_length,
                      meshes[i]);
  }
}

void Tessellator::tessellateChecked(const Vec3* control_points, int columns, int rows, double hair_length,
                                    StripMesh& mesh) {
  const int n_u = verticesAcross(columns, level_of_detail_);
  const int n_v = verticesAlong(rows, level_of_detail_);
  prepareMesh(mesh, n_u, n_v, uParam(n_u, n_v));
  switch (method_) {
    case TessellationMethod::ForwardDifferencing:
      tessellateForwardDifferencing(control_points, columns, rows, hair_length, mesh);
      break;
    case TessellationMethod::DeBoor:
      tessellateDeBoor(control_points, columns, rows, hair_length, mesh);
      break;
    case TessellationMethod::CachedBasis:
      tessellateCachedBasis(control_points, columns, rows, hair_length, mesh);
      break;
  }
}

void Tessellator::tessellateForwardDifferencing(const Vec3* points, int columns, int rows, double hair_length,
                                                StripMesh& mesh) {
  const BasisTable& across = acrossTable(columns);  // only its sample -> polynomial piece partition is used
  const int degree = across.width - 1;
  const int samples_along = level_of_detail_.samples_along;
  const double step_u = 1.0 / static_cast<double>(level_of_detail_.samples_across);
  const double step_v = 1.0 / static_cast<double>(samples_along);
  const double scale_u = static_cast<double>(columns - 1);
  const double scale_v = static_cast<double>(rows - 1);
  const int n_u = mesh.n_u;
  const double inverse_length = 1.0 / hair_length;
  walks_.resize(static_cast<std::size_t>(n_u));

  for (int span = 0; span < rows - 1; ++span) {
    int iu = 0;
    while (iu < n_u) {
      // One polynomial piece across u: the samples iu..end share it.
      const int piece = across.samples[static_cast<std::size_t>(iu)].piece;
      int end = iu + 1;
      while (end < n_u && across.samples[static_cast<std::size_t>(end)].piece == piece) {
        ++end;
      }
      const double s0 = across.samples[static_cast<std::size_t>(iu)].s;
      const int first_column = degree == 1 ? piece : piece - 1;

      // Power basis along v of each (extended) control column of the patch: V[b][k] multiplies t^k.
      Vec3 along[4][4];
      for (int b = 0; b <= degree; ++b) {
        const Vec3 g0 = extendedPoint(points, columns, rows, first_column + b, span - 1);
        const Vec3 g1 = extendedPoint(points, columns, rows, first_column + b, span);
        const Vec3 g2 = extendedPoint(points, columns, rows, first_column + b, span + 1);
        const Vec3 g3 = extendedPoint(points, columns, rows, first_column + b, span + 2);
        along[b][3] = (-g0 + 3.0 * g1 - 3.0 * g2 + g3) / 6.0;
        along[b][2] = 0.5 * (g0 + g2) - g1;
        along[b][1] = 0.5 * (g2 - g0);
        along[b][0] = (g0 + 4.0 * g1 + g2) / 6.0;
      }
      // Power basis across u: coefficient[k][m] multiplies s^m t^k; derivative[k][m] is d/ds of it.
      Vec3 coefficient[4][4];
      Vec3 derivative[4][4];
      for (int k = 0; k < 4; ++k) {
        const Vec3& v0 = along[0][k];
        const Vec3& v1 = along[1][k];
        Vec3* c = coefficient[k];
        c[0] = c[1] = c[2] = c[3] = Vec3::Zero();
        if (degree == 1) {
          c[0] = v0;
          c[1] = v1 - v0;
        } else if (degree == 2) {
          const Vec3& v2 = along[2][k];
          c[0] = 0.5 * (v0 + v1);
          c[1] = v1 - v0;
          c[2] = 0.5 * (v0 + v2) - v1;
        } else {
          const Vec3& v2 = along[2][k];
          const Vec3& v3 = along[3][k];
          c[0] = (v0 + 4.0 * v1 + v2) / 6.0;
          c[1] = 0.5 * (v2 - v0);
          c[2] = 0.5 * (v0 + v2) - v1;
          c[3] = (-v0 + 3.0 * v1 - 3.0 * v2 + v3) / 6.0;
        }
        Vec3* d = derivative[k];
        d[0] = c[1];
        d[1] = 2.0 * c[2];
        d[2] = 3.0 * c[3];
        d[3] = Vec3::Zero();
      }
      // Forward differences in u of the v-curve coefficients (position and d/ds).
      ForwardDifferences across_fd[4];
      ForwardDifferences across_du_fd[4];
      for (int k = 0; k < 4; ++k) {
        across_fd[k] = initForwardDifferencesFrom(coefficient[k], s0, step_u);
        across_du_fd[k] = initForwardDifferencesFrom(derivative[k], s0, step_u);
      }

      for (; iu < end; ++iu) {
        // The curve along v at this u: f(t) = a t^3 + b t^2 + c t + d; its d/du and d/dv curves.
        const Vec3& a = across_fd[3].f;
        const Vec3& b = across_fd[2].f;
        const Vec3& c = across_fd[1].f;
        const Vec3& d = across_fd[0].f;
        ColumnWalk& walk = walks_[static_cast<std::size_t>(iu)];
        if (span == 0 || !walk.clipped) {
          ForwardDifferences curve = initForwardDifferences(a, b, c, d, step_v);
          ForwardDifferences curve_du =
              initForwardDifferences(across_du_fd[3].f * scale_u, across_du_fd[2].f * scale_u,
                                     across_du_fd[1].f * scale_u, across_du_fd[0].f * scale_u, step_v);
          ForwardDifferences curve_dv = initForwardDifferences(Vec3::Zero(), (3.0 * scale_v) * a,
                                                               (2.0 * scale_v) * b, scale_v * c, step_v);
          int iv = span * samples_along;
          if (span == 0) {
            emitVertex(walk, iu, iv, curve.f, Vec3::Zero(), curve_du.f, curve_dv.f, hair_length,
                       inverse_length, mesh);
          }
          for (int m = 1; m <= samples_along && !walk.clipped; ++m) {
            const Vec3 step = curve.d1;
            curve.step();
            curve_du.step();
            curve_dv.step();
            emitVertex(walk, iu, ++iv, curve.f, step, curve_du.f, curve_dv.f, hair_length, inverse_length,
                       mesh);
          }
        }
        for (int k = 0; k < 4; ++k) {
          across_fd[k].step();
          across_du_fd[k].step();
        }
      }
    }
  }
  normalizeFrames(mesh.normals.data(), mesh.tangents.data(), mesh.positions.size());
}

void Tessellator::tessellateDeBoor(const Vec3* points, int columns, int rows, double hair_length,
                                   StripMesh& mesh) {
  const BSplineSurface surface(points, columns, rows);
  const int n_u = mesh.n_u;
  const int n_v = mesh.n_v;
  const double inverse_u = 1.0 / static_cast<double>(n_u - 1);
  const double inverse_v = 1.0 / static_cast<double>(n_v - 1);
  const double inverse_length = 1.0 / hair_length;
  Vec3 position;
  Vec3 d_du;
  Vec3 d_dv;
  for (int iu = 0; iu < n_u; ++iu) {
    const double u = iu == n_u - 1 ? 1.0 : static_cast<double>(iu) * inverse_u;
    ColumnWalk walk;
    for (int iv = 0; iv < n_v && !walk.clipped; ++iv) {
      const double v = iv == n_v - 1 ? 1.0 : static_cast<double>(iv) * inverse_v;
      surface.evaluate(u, v, position, d_du, d_dv);
      emitVertex(walk, iu, iv, position, position - walk.position, d_du, d_dv, hair_length, inverse_length,
                 mesh);
    }
  }
  normalizeFrames(mesh.normals.data(), mesh.tangents.data(), mesh.positions.size());
}

void Tessellator::tessellateCachedBasis(const Vec3* points, int columns, int rows, double hair_length,
                                        StripMesh& mesh) {
  const BasisTable& across = acrossTable(columns);
  const BasisTable& along = alongTable(rows);
  const int n_u = mesh.n_u;
  const int n_v = mesh.n_v;
  const double inverse_length = 1.0 / hair_length;
  const double* control = points->data();
#if defined(HAIR_SIM_AVX2)
  if (cpuHasAvx2()) {
    const LaneGroups& groups = along.quads;
    const int quads = static_cast<int>(groups.first.size());
    const int stride = 4 * quads;
    const std::size_t curve_size = static_cast<std::size_t>(3 * columns) * static_cast<std::size_t>(stride);
    if (curve_.size() < curve_size) {
      curve_.resize(curve_size);
      curve_dv_.resize(curve_size);
    }
    const int* first = groups.first.data();
    const double* weight = groups.weight.data();
    const double* derivative = groups.derivative.data();
    switch (groups.window) {
      case 4:
        columnCurveQuads<4>(control, columns, quads, first, weight, derivative, stride, curve_.data(),
                            curve_dv_.data());
        break;
      case 5:
        columnCurveQuads<5>(control, columns, quads, first, weight, derivative, stride, curve_.data(),
                            curve_dv_.data());
        break;
      case 6:
        columnCurveQuads<6>(control, columns, quads, first, weight, derivative, stride, curve_.data(),
                            curve_dv_.data());
        break;
      default:
        columnCurveQuads<7>(control, columns, quads, first, weight, derivative, stride, curve_.data(),
                            curve_dv_.data());
        break;
    }
    for (int iu = 0; iu < n_u;) {
      const BasisSample& sample = across.samples[static_cast<std::size_t>(iu)];
      const std::size_t offset = static_cast<std::size_t>(3 * sample.first) * stride;
      const double* curve = curve_.data() + offset;
      const double* curve_dv = curve_dv_.data() + offset;
      // Three or four vertex columns on the same control columns go through the rows kernel together.
      int count = 1;
      while (count < 4 && iu + count < n_u &&
             across.samples[static_cast<std::size_t>(iu + count)].first == sample.first) {
        ++count;
      }
      if (count >= kMinRowLanes) {
        const double* weights[4];
        const double* derivatives[4];
        for (int l = 0; l < count; ++l) {
          weights[l] = across.samples[static_cast<std::size_t>(iu + l)].weight;
          derivatives[l] = across.samples[static_cast<std::size_t>(iu + l)].derivative;
        }
        switch (across.width) {
          case 2:
            cachedRowQuads<2>(curve, curve_dv, stride, weights, derivatives, iu, count, hair_length,
                              inverse_length, mesh);
            break;
          case 3:
            cachedRowQuads<3>(curve, curve_dv, stride, weights, derivatives, iu, count, hair_length,
                              inverse_length, mesh);
            break;
          default:
            cachedRowQuads<4>(curve, curve_dv, stride, weights, derivatives, iu, count, hair_length,
                              inverse_length, mesh);
            break;
        }
        iu += count;
        continue;
      }
      switch (across.width) {
        case 2:
          cachedColumnQuads<2>(curve, curve_dv, stride, sample.weight, sample.derivative, iu, hair_length,
                               inverse_length, mesh);
          break;
        case 3:
          cachedColumnQuads<3>(curve, curve_dv, stride, sample.weight, sample.derivative, iu, hair_length,
                               inverse_length, mesh);
          break;
        default:
          cachedColumnQuads<4>(curve, curve_dv, stride, sample.weight, sample.derivative, iu, hair_length,
                               inverse_length, mesh);
          break;
      }
      ++iu;
    }
    return;
  }
#endif
#if defined(HAIR_SIM_SSE2)
  // Stage 1: column curves, two v samples per step, coordinate arrays over the (even) sample count.
  const int pairs = (n_v + 1) / 2;
  const int stride = 2 * pairs;
  const std::size_t broadcast_size = static_cast<std::size_t>(6 * columns * rows);
  const std::size_t curve_size = static_cast<std::size_t>(3 * columns) * static_cast<std::size_t>(stride);
  if (broadcast_.size() < broadcast_size) {
    broadcast_.resize(broadcast_size);
  }
  if (curve_.size() < curve_size) {
    curve_.resize(curve_size);
    curve_dv_.resize(curve_size);
  }
  for (std::size_t i = 0; i < broadcast_size / 2; ++i) {
    broadcast_[2 * i] = control[i];
    broadcast_[2 * i + 1] = control[i];
  }
  const LaneGroups& groups = along.pairs;
  switch (groups.window) {
    case 4:
      columnCurvePairs<4>(broadcast_.data(), columns, pairs, groups.first.data(), groups.weight.data(),
                          groups.derivative.data(), stride, curve_.data(), curve_dv_.data());
      break;
    default:
      columnCurvePairs<5>(broadcast_.data(), columns, pairs, groups.first.data(), groups.weight.data(),
                          groups.derivative.data(), stride, curve_.data(), curve_dv_.data());
      break;
  }
  // Stage 2: each vertex column combines (degree + 1) column curves across u and walks the length.
  for (int iu = 0; iu < n_u; ++iu) {
    const BasisSample& sample = across.samples[static_cast<std::size_t>(iu)];
    const std::size_t offset = static_cast<std::size_t>(3 * sample.first) * stride;
    const double* curve = curve_.data() + offset;
    const double* curve_dv = curve_dv_.data() + offset;
    switch (across.width) {
      case 2:
        cachedColumnPairs<2>(curve, curve_dv, stride, sample.weight, sample.derivative, iu, hair_length,
                             inverse_length, mesh);
        break;
      case 3:
        cachedColumnPairs<3>(curve, curve_dv, stride, sample.weight, sample.derivative, iu, hair_length,
                             inverse_length, mesh);
        break;
      default:
        cachedColumnPairs<4>(curve, curve_dv, stride, sample.weight, sample.derivative, iu, hair_length,
                             inverse_length, mesh);
        break;
    }
  }
#else
  const int row_stride = 3 * columns;  // a control row is 3 * columns contiguous doubles
  // Stage 1: every control column's curve and its d/dv at every v sample: 4 weights on 4 control rows.
  const std::size_t curve_size = static_cast<std::size_t>(n_v) * static_cast<std::size_t>(row_stride);
  if (curve_.size() < curve_size) {
    curve_.resize(curve_size);
    curve_dv_.resize(curve_size);
  }
  switch (columns) {
    case 2:
      columnCurves<6>(control, along, n_v, 6, curve_.data(), curve_dv_.data());
      break;
    case 3:
      columnCurves<9>(control, along, n_v, 9, curve_.data(), curve_dv_.data());
      break;
    case 4:
      columnCurves<12>(control, along, n_v, 12, curve_.data(), curve_dv_.data());
      break;
    default:
      columnCurves<0>(control, along, n_v, row_stride, curve_.data(), curve_dv_.data());
      break;
  }
  // Stage 2: each vertex column combines (degree + 1) column curves across u and walks the length.
  for (int iu = 0; iu < n_u; ++iu) {
    const BasisSample& sample = across.samples[static_cast<std::size_t>(iu)];
    const double* curve = curve_.data() + 3 * sample.first;
    const double* curve_dv = curve_dv_.data() + 3 * sample.first;
    switch (across.width) {
      case 2:
        cachedColumn<2>(curve, curve_dv, row_stride, sample.weight, sample.derivative, iu, hair_length,
                        inverse_length, mesh);
        break;
      case 3:
        cachedColumn<3>(curve, curve_dv, row_stride, sample.weight, sample.derivative, iu, hair_length,
                        inverse_length, mesh);
        break;
      default:
        cachedColumn<4>(curve, curve_dv, row_stride, sample.weight, sample.derivative, iu, hair_length,
                        inverse_length, mesh);
        break;
    }
  }
  normalizeFrames(mesh.normals.data(), mesh.tangents.data(), mesh.positions.size());
#endif
}

void Tessellator::tessellateCachedBasisLanes(const StripInput* strips, StripMesh* meshes) {
#if defined(HAIR_SIM_AVX2)
  const int columns = strips[0].columns;
  const int rows = strips[0].rows;
  const BasisTable& across = acrossTable(columns);
  const BasisTable& along = alongTable(rows);
  const int n_u = meshes[0].n_u;
  const std::size_t coordinates = 3 * static_cast<std::size_t>(columns) * static_cast<std::size_t>(rows);
  if (lane_control_.size() < 4 * coordinates) {
    lane_control_.resize(4 * coordinates);
  }
  const double* const control[4] = {strips[0].control_points->data(), strips[1].control_points->data(),
                                    strips[2].control_points->data(), strips[3].control_points->data()};
  interleaveStrips(control, coordinates, lane_control_.data());
  const LaneGroups& groups = along.quads;
  double hair_length[4];
  double inverse_length[4];
  for (int l = 0; l < 4; ++l) {
    hair_length[l] = strips[l].hair_length;
    inverse_length[l] = 1.0 / strips[l].hair_length;
  }
  const double* weights[4];
  for (int iu = 0; iu < n_u; ++iu) {
    weights[iu] = across.samples[static_cast<std::size_t>(iu)].weight;
  }
  // (One linear span across: every sample's derivative weights are sample 0's. The batch tests compare with
  // the per-strip kernels, which take each sample's own.)
  const double* derivative = across.samples.front().derivative;
  // The quads' window: 4 control rows at 4 or more samples along, up to 7 at 1.
  auto run = [&](auto kernel) {
    kernel(lane_control_.data(), groups.first.data(), groups.weight.data(), groups.derivative.data(), weights,
           derivative, hair_length, inverse_length, meshes);
  };
  auto withWindow = [&](auto nu) {
    constexpr int NU = decltype(nu)::value;
    switch (groups.window) {
      case 4:
        run(stripRows<4, NU>);
        break;
      case 5:
        run(stripRows<5, NU>);
        break;
      case 6:
        run(stripRows<6, NU>);
        break;
      default:
        run(stripRows<7, NU>);
        break;
    }
  };
  switch (n_u) {
    case 2:
      withWindow(std::integral_constant<int, 2>{});
      break;
    case 3:
      withWindow(std::integral_constant<int, 3>{});
      break;
    default:
      withWindow(std::integral_constant<int, 4>{});
      break;
  }
#else
  (void)strips;  // only called where the AVX2 kernels are compiled
  (void)meshes;
#endif
}

}  // namespace hair_sim
