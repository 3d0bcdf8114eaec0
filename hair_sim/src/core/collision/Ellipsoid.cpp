#include "hair_sim/core/collision/Ellipsoid.hpp"

#include <Eigen/SVD>

#include <charconv>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

namespace hair_sim {
namespace {

constexpr double kRotationTolerance = 1e-6;
/// transformed(): a pose's rotation this close to orthonormal is replaced by the nearest rotation.
constexpr double kPoseTolerance = 1e-4;
/// Above this deviation from orthonormality the accepted rotation is replaced by the nearest rotation
/// (polar factor), so that S, Sinv and the local frame used by closestPoint agree to rounding.
constexpr double kReorthonormaliseAbove = 1e-12;
/// Bound on the safeguarded Newton/bisection iterations of closestPoint (typically 3-15 are used).
constexpr int kMaxRootIterations = 100;
constexpr double kEps = std::numeric_limits<double>::epsilon();

/// Shortest representation that reads back to the same double (e.g. -0.3, nan, inf).
std::string format(double v) {
  char buf[64];
  const std::to_chars_result r = std::to_chars(buf, buf + sizeof(buf), v);
  return std::string(buf, r.ptr);
}

std::string format(const Vec3& v) {
  return "(" + format(v.x()) + ", " + format(v.y()) + ", " + format(v.z()) + ")";
}

std::string format(const Mat3& m) {
  std::string s = "[";
  for (int r = 0; r < 3; ++r) {
    s += (r == 0 ? "[" : ", [") + format(m(r, 0)) + ", " + format(m(r, 1)) + ", " + format(m(r, 2)) + "]";
  }
  return s + "]";
}

/// Indices of the radii sorted by decreasing length (stable for ties).
void sortAxesDescending(const Vec3& radii, int idx[3]) {
  idx[0] = 0;
  idx[1] = 1;
  idx[2] = 2;
  if (radii[idx[0]] < radii[idx[1]]) std::swap(idx[0], idx[1]);
  if (radii[idx[1]] < radii[idx[2]]) std::swap(idx[1], idx[2]);
  if (radii[idx[0]] < radii[idx[1]]) std::swap(idx[0], idx[1]);
}

}  // namespace

Ellipsoid::Ellipsoid() : Ellipsoid(Vec3::Zero(), Mat3::Identity(), Vec3::Ones()) {}

Ellipsoid::Ellipsoid(const Vec3& center, const Mat3& rotation, const Vec3& radii) {
  static const std::string kPrefix = "Ellipsoid::Ellipsoid(...) : ";
  if (!center.allFinite()) {
    throw std::invalid_argument(kPrefix + "centre must be finite, got " + format(center));
  }
  for (int i = 0; i < 3; ++i) {
    if (!(std::isfinite(radii[i]) && radii[i] > 0.0)) {
      throw std::invalid_argument(kPrefix + "radius " + std::to_string(i) + " must be finite and > 0, got " +
                                  format(radii[i]) + " (radii " + format(radii) + ")");
    }
  }
  if (!rotation.allFinite()) {
    throw std::invalid_argument(kPrefix + "rotation must be finite, got " + format(rotation));
  }
  const double ortho_error = (rotation.transpose() * rotation - Mat3::Identity()).cwiseAbs().maxCoeff();
  const double det = rotation.determinant();
  if (!(ortho_error <= kRotationTolerance) || !(det > 0.0)) {
    throw std::invalid_argument(kPrefix + "rotation must be orthonormal with det +1 (tolerance " +
                                format(kRotationTolerance) + "), got max|R^T R - I| = " +
                                format(ortho_error) + ", det = " + format(det) + ", R = " + format(rotation));
  }
  if (ortho_error > kReorthonormaliseAbove) {
    const Eigen::JacobiSVD<Mat3> svd(rotation, Eigen::ComputeFullU | Eigen::ComputeFullV);
    rotation_ = svd.matrixU() * svd.matrixV().transpose();
  } else {
    rotation_ = rotation;
  }
  center_ = center;
  radii_ = radii;
  S_ = rotation_ * radii_.asDiagonal();
  Sinv_ = radii_.cwiseInverse().asDiagonal() * rotation_.transpose();
}

Ellipsoid Ellipsoid::fromRpy(const Vec3& center, const Vec3& rpy, const Vec3& radii) {
  if (!rpy.allFinite()) {
    throw std::invalid_argument("Ellipsoid::fromRpy(...) : rpy must be finite, got " + format(rpy));
  }
  return Ellipsoid(center, rotationFromRpy(rpy), radii);
}

Ellipsoid Ellipsoid::inflated(double margin) const {
  const Vec3 radii = radii_.array() + margin;
  if (!std::isfinite(margin) || !(radii.minCoeff() > 0.0)) {
    throw std::invalid_argument("Ellipsoid::inflated(...) : margin " + format(margin) +
                                " must be finite and leave every radius > 0, radii " + format(radii_) +
                                " would become " + format(radii));
  }
  return Ellipsoid(center_, rotation_, radii);
}

Ellipsoid Ellipsoid::transformed(const Iso3& pose) const {
  // Poses come from tf: a quaternion whose norm is off 1 by a few 1e-7 (float rounding, within what the
  // node and tf2 accept) gives a matrix just outside kRotationTolerance. Such a pose is taken as its
  // nearest rotation; one further off is still an error (found by fuzz_messages).
  // A rotation orthonormal to rounding (every pose from a unit quaternion) is taken as it is: no SVD, which
  // was most of the cost of the bodies' poses in every substep.
  const Mat3& r = pose.linear();
  const double deviation = (r.transpose() * r - Mat3::Identity()).cwiseAbs().maxCoeff();
  if (r.allFinite() && deviation <= kPoseTolerance && r.determinant() > 0.0) {
    if (deviation <= kReorthonormaliseAbove) return Ellipsoid(pose * center_, r * rotation_, radii_);
    const Eigen::JacobiSVD<Mat3> svd(r, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Mat3 nearest = svd.matrixU() * svd.matrixV().transpose();  // polar factor
    return Ellipsoid(pose * center_, nearest * rotation_, radii_);
  }
  return Ellipsoid(pose * center_, r * rotation_, radii_);
}

/// At the centre itself (the gradient vanishes) the +direction of the smallest axis is returned, the
/// same choice closestPoint makes for the centre.
Vec3 Ellipsoid::normalAt(const Vec3& p) const {
  const Vec3 local = rotation_.transpose() * (p - center_);
  const Vec3 gradient = local.cwiseQuotient(radii_.cwiseAbs2());
  const double norm = gradient.norm();
  if (!(norm > 0.0)) {
    int idx[3];
    sortAxesDescending(radii_, idx);
    return rotation_.col(idx[2]);
  }
  return rotation_ * (gradient / norm);
}

/// For p at the centre (toSphere(p) == 0) the end of the local +x semi-axis, centre + S * (1, 0, 0),
/// is returned.
Vec3 Ellipsoid::radialProjection(const Vec3& p) const {
  const Vec3 q = toSphere(p);
  const double norm = q.norm();
  if (!(norm > 0.0)) return center_ + S_.col(0);
  return center_ + S_ * (q / norm);
}

/// Eberly, "Distance from a Point to an Ellipse, an Ellipsoid, or a Hyperellipsoid": in the local frame,
/// reflected into the first octant and with the axes sorted e0 >= e1 >= e2, the closest point is
/// x_i = e_i^2 y_i / (t + e_i^2) where the multiplier t > -e2^2 is the root of
///   F(t) = sum_i (e_i y_i / (t + e_i^2))^2 - 1
/// (t > 0 outside, t in (-e2^2, 0) inside). We use the shifted, scaled unknown u = (t + e2^2) / e2^2 > 0,
///   G(u) = sum_i (a_i / (u + d_i))^2 - 1,  a_i = e_i y_i / e2^2,  d_i = (e_i^2 - e2^2) / e2^2 >= 0,
/// so that every denominator is a sum of non-negative numbers (no cancellation) and a tiny root (points
/// inside, close to the plane of the two large axes) keeps full relative precision. G is decreasing and
/// convex on u > 0 and has a single root there when y2 > 0, bracketed by
///   lo = max(0, max_i(a_i - d_i)) (one term alone equals 1, so G(lo) >= 0) and hi = max(1, |a|) (G <= 0).
/// Instead of plain bisection the root is found with Newton's method on psi(u) = (G(u) + 1)^(-1/2), which is
/// concave and nearly linear (More-Sorensen), started at lo: the iterates increase monotonically towards
/// the root; bisection of the bracket is the safeguard. When y2 == 0 and G(0) <= 0 (inside, within the
/// evolute) the multiplier is t = -e2^2 (u = 0) and x2 = e2 sqrt(1 - (x0/e0)^2 - (x1/e1)^2); at the centre
/// this picks the end of the smallest semi-axis (in its + direction).
Ellipsoid::ClosestPoint Ellipsoid::closestPoint(const Vec3& p) const {
  const Vec3 local = rotation_.transpose() * (p - center_);
  int idx[3];
  sortAxesDescending(radii_, idx);

  double e[3];
  double y[3];
  for (int i = 0; i < 3; ++i) {
    e[i] = radii_[idx[i]];
    y[i] = std::abs(local[idx[i]]);
  }
  const double e2_sq = e[2] * e[2];
  double a[3];
  double d[3];
  double a_norm_sq = 0.0;
  double g = -1.0;
  for (int i = 0; i < 3; ++i) {
    a[i] = e[i] * y[i] / e2_sq;
    d[i] = (e[i] - e[2]) * (e[i] + e[2]) / e2_sq;
    a_norm_sq += a[i] * a[i];
    const double z = y[i] / e[i];
    g += z * z;
  }

  double x[3];
  if (g == 0.0) {
    for (int i = 0; i < 3; ++i) x[i] = y[i];
  } else {
    bool on_evolute_plane = false;
    if (y[2] == 0.0) {
      // G(0) with the third term absent; infinite if a term with d_i == 0 has a_i > 0.
      double g0 = -1.0;
      for (int i = 0; i < 2; ++i) {
        if (a[i] == 0.0) continue;
        if (d[i] == 0.0) {
          g0 = std::numeric_limits<double>::infinity();
          break;
        }
        const double r = a[i] / d[i];
        g0 += r * r;
      }
      if (g0 <= 0.0) {
        on_evolute_plane = true;
        double rest = 1.0;
        for (int i = 0; i < 2; ++i) {
          x[i] = a[i] == 0.0 ? 0.0 : e[i] * a[i] / d[i];
          const double xi = x[i] / e[i];
          rest -= xi * xi;
        }
        x[2] = e[2] * std::sqrt(rest > 0.0 ? rest : 0.0);
      }
    }
    if (!on_evolute_plane) {
      double lo = 0.0;
      for (int i = 0; i < 3; ++i) {
        if (a[i] - d[i] > lo) lo = a[i] - d[i];
      }
      double hi = std::sqrt(a_norm_sq);
      if (hi < 1.0) hi = 1.0;
      if (hi < lo) hi = lo;
      double u = lo;
      for (int it = 0; it < kMaxRootIterations; ++it) {
        double q = 0.0;   // G(u) + 1
        double s3 = 0.0;  // -G'(u) / 2
        for (int i = 0; i < 3; ++i) {
          if (a[i] == 0.0) continue;
          const double inv = 1.0 / (u + d[i]);
          const double r = a[i] * inv;
          q += r * r;
          s3 += r * r * inv;
        }
        if (q > 1.0) {
          lo = u;
        } else if (q < 1.0) {
          hi = u;
        } else {
          break;  // exact root, or NaN input
        }
        // Newton step on psi: forwards from below the root (never past it, psi is concave), backwards
        // (to below it) from above. Stop when the step is at the level of the rounding noise of u or
        // of q (eps q propagates to about eps q / (2 s3) in u; this bounds the answer's error too).
        const double step = q * (std::sqrt(q) - 1.0) / s3;
        const double noise = 4.0 * kEps * (u > q / s3 ? u : q / s3);
        if (!(std::abs(step) > noise)) break;
        double next = u + step;
        if (step > 0.0 && next >= hi) {
          // Only by rounding: the root is hi to within a few ulps (a sphere, a far point on an axis).
          u = hi;
          break;
        }
        if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
        if (!(next > lo && next < hi)) break;  // the bracket cannot shrink any more
        u = next;
      }
      for (int i = 0; i < 3; ++i) x[i] = a[i] == 0.0 ? 0.0 : e[i] * a[i] / (u + d[i]);
    }
  }

  Vec3 closest_local;
  Vec3 gradient_local;
  for (int i = 0; i < 3; ++i) {
    const int k = idx[i];
    closest_local[k] = std::copysign(x[i], local[k]);
    gradient_local[k] = closest_local[k] / (e[i] * e[i]);
  }
  ClosestPoint result;
  result.point = center_ + rotation_ * closest_local;
  result.normal = rotation_ * gradient_local.normalized();
  const double distance = (closest_local - local).norm();
  result.signed_distance = implicitValue(p) < 0.0 ? -distance : distance;
  return result;
}

/// Solves |A + t D|^2 = 1 in sphere space (A = toSphere(a), D = toSphere(b) - A). A path that only
/// touches the surface (tangent, or starting on it and moving outwards or along it) does not enter.
bool Ellipsoid::firstHit(const Vec3& a, const Vec3& b, double* t_enter) const {
  const Vec3 sa = toSphere(a);
  const double c = sa.squaredNorm() - 1.0;
  if (c < 0.0) {
    if (t_enter != nullptr) *t_enter = 0.0;
    return true;
  }
  const Vec3 dir = Sinv_ * (b - a);
  const double aa = dir.squaredNorm();
  const double half_b = sa.dot(dir);
  if (!(aa > 0.0) || !(half_b < 0.0)) return false;  // not moving, moving away, or NaN
  // Discriminant / 4 = half_b^2 - aa * c = aa - |sa x dir|^2 (Lagrange identity, no cancellation
  // between two large terms).
  const double disc = aa - sa.cross(dir).squaredNorm();
  if (!(disc > 0.0)) return false;
  // Smaller root of aa t^2 + 2 half_b t + c = 0 in the cancellation-free form c / q.
  const double t = c / (-half_b + std::sqrt(disc));
  if (!(t <= 1.0)) return false;
  if (t_enter != nullptr) *t_enter = t;
  return true;
}

/// Pure arithmetic (no validation, it runs in the hot loop): non-finite inputs give non-finite output.
Vec3 reactionForce(const Vec3& f_in, const Vec3& normal, double depth, const Vec3& velocity, double k,
                   double c) {
  return f_in - f_in.dot(normal) * normal - (k * depth + c * velocity.dot(normal)) * normal;
}

}  // namespace hair_sim
