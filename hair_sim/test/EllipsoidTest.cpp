#include "hair_sim/core/collision/Ellipsoid.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace hair_sim {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

/// Portable uniform numbers from a fixed-seed engine (std::uniform_real_distribution is not specified
/// bit-for-bit across standard libraries).
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : engine_(seed) {}
  double uniform(double lo, double hi) {
    return lo + (hi - lo) * static_cast<double>(engine_() >> 11) * 0x1.0p-53;
  }
  Vec3 unitVector() {
    for (;;) {
      const Vec3 v(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1));
      const double n = v.norm();
      if (n > 0.1 && n <= 1.0) return v / n;
    }
  }

 private:
  std::mt19937_64 engine_;
};

/// Expects fn() to throw std::invalid_argument whose what() contains every string of `parts`.
template <typename Fn>
void expectInvalidArgument(Fn fn, const std::vector<std::string>& parts) {
  try {
    fn();
    ADD_FAILURE() << "no exception thrown";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    for (const std::string& part : parts) {
      EXPECT_NE(what.find(part), std::string::npos) << "'" << part << "' not in: " << what;
    }
  }
}

// ---------------------------------------------------------------------------------------------------------
// Brute-force reference for the closest surface point, independent of the implementation: a dense grid over
// the six cube-face charts of the surface (x = diag(radii) m / |m|, m = (+-1, u, v) and permutations), each
// grid-local minimum refined by a shrinking-window pattern search and then by Newton's method on the
// analytic gradient of the squared distance (finite-difference Hessian). The reference is accurate to ~1e-15
// wherever the minimum is well conditioned (see Reference::unique).
// ---------------------------------------------------------------------------------------------------------
struct Reference {
  Vec3 point;       // world
  double distance;  // unsigned
  /// False when another local minimum at a different place (> 1e-6 m away) is within 1e-12 m in distance,
  /// or the minimum is nearly flat: then the closest point is not unique to test precision and only the
  /// distance is compared.
  bool unique;
};

class BruteForce {
 public:
  BruteForce(const Ellipsoid& ellipsoid, const Vec3& p)
      : ellipsoid_(ellipsoid),
        e_(ellipsoid.radii()),
        y_(ellipsoid.rotation().transpose() * (p - ellipsoid.center())),
        ea_{e_.x(), e_.y(), e_.z()},
        ya_{y_.x(), y_.y(), y_.z()} {}

  Reference solve() const {
    constexpr int kN = 64;
    const double h = 2.0 / kN;
    struct Candidate {
      int face;
      double u, v, f;
    };
    std::vector<Candidate> candidates;
    std::vector<double> grid(kN * kN);
    for (int face = 0; face < 6; ++face) {
      for (int i = 0; i < kN; ++i) {
        for (int j = 0; j < kN; ++j) {
          grid[i * kN + j] = f(face, -1.0 + (i + 0.5) * h, -1.0 + (j + 0.5) * h);
        }
      }
      for (int i = 0; i < kN; ++i) {
        for (int j = 0; j < kN; ++j) {
          const double fij = grid[i * kN + j];
          bool local_min = true;
          for (int di = -1; di <= 1 && local_min; ++di) {
            for (int dj = -1; dj <= 1; ++dj) {
              const int ii = i + di;
              const int jj = j + dj;
              if ((di == 0 && dj == 0) || ii < 0 || jj < 0 || ii >= kN || jj >= kN) continue;
              if (grid[ii * kN + jj] < fij) {
                local_min = false;
                break;
              }
            }
          }
          if (local_min) candidates.push_back({face, -1.0 + (i + 0.5) * h, -1.0 + (j + 0.5) * h, fij});
        }
      }
    }
    // Refine (the grid-local minima can be many on flat valleys: keep the 16 best).
    std::sort(candidates.begin(), candidates.end(),
              [](const Candidate& a, const Candidate& b) { return a.f < b.f; });
    if (candidates.size() > 16) candidates.resize(16);
    std::vector<Vec3> points;
    std::vector<double> distances;
    for (Candidate& c : candidates) {
      refine(h, &c.face, &c.u, &c.v);
      points.push_back(chart(c.face, c.u, c.v));
      distances.push_back(std::sqrt(f(c.face, c.u, c.v)));
    }
    std::size_t best = 0;
    for (std::size_t k = 1; k < points.size(); ++k) {
      if (distances[k] < distances[best]) best = k;
    }
    Reference ref;
    ref.point = ellipsoid_.center() + ellipsoid_.rotation() * points[best];
    ref.distance = distances[best];
    // A nearly flat minimum (e.g. close to the axis of a spheroid, where the closest points form an almost
    // perfect circle) pins the point down only as far as rounding allows: not unique either.
    ref.unique = smallestCurvature(candidates[best].face, candidates[best].u, candidates[best].v) > 1e-6;
    for (std::size_t k = 0; k < points.size(); ++k) {
      if ((points[k] - points[best]).norm() > 1e-6 && distances[k] - distances[best] < 1e-12) {
        ref.unique = false;
      }
    }
    return ref;
  }

 private:
  static void axes(int face, int* k, double* sign) {
    *k = face / 2;
    *sign = (face % 2 == 0) ? 1.0 : -1.0;
  }
  Vec3 direction(int face, double u, double v) const {
    int k;
    double s;
    axes(face, &k, &s);
    Vec3 m;
    m[k] = s;
    m[(k + 1) % 3] = u;
    m[(k + 2) % 3] = v;
    return m;
  }
  Vec3 chart(int face, double u, double v) const {
    return e_.cwiseProduct(direction(face, u, v).normalized());
  }
  /// Squared distance, in plain doubles (this is the inner loop; Eigen is slow in unoptimised builds).
  double f(int face, double u, double v) const {
    const int k = face / 2;
    double m[3];
    m[k] = (face % 2 == 0) ? 1.0 : -1.0;
    m[(k + 1) % 3] = u;
    m[(k + 2) % 3] = v;
    const double inv = 1.0 / std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
    double sum = 0.0;
    for (int i = 0; i < 3; ++i) {
      const double d = ea_[i] * m[i] * inv - ya_[i];
      sum += d * d;
    }
    return sum;
  }
  Eigen::Vector2d gradient(int face, double u, double v) const {
    int k;
    double s;
    axes(face, &k, &s);
    const Vec3 m = direction(face, u, v);
    const double len = m.norm();
    const Vec3 n = m / len;
    const Vec3 bu = Vec3::Unit((k + 1) % 3);
    const Vec3 bv = Vec3::Unit((k + 2) % 3);
    const Vec3 dx_du = e_.cwiseProduct((bu - n * n.dot(bu)) / len);
    const Vec3 dx_dv = e_.cwiseProduct((bv - n * n.dot(bv)) / len);
    const Vec3 r = e_.cwiseProduct(n) - y_;
    return Eigen::Vector2d(2.0 * r.dot(dx_du), 2.0 * r.dot(dx_dv));
  }
  Eigen::Matrix2d hessian(int face, double u, double v) const {
    const double fd = 1e-6;
    Eigen::Matrix2d hess;
    hess.col(0) = (gradient(face, u + fd, v) - gradient(face, u - fd, v)) / (2 * fd);
    hess.col(1) = (gradient(face, u, v + fd) - gradient(face, u, v - fd)) / (2 * fd);
    return hess;
  }
  /// Smallest second derivative of the squared distance per square metre along the surface at a minimum.
  double smallestCurvature(int face, double u, double v) const {
    const double d = 1e-7;
    Eigen::Matrix<double, 3, 2> jac;
    jac.col(0) = (chart(face, u + d, v) - chart(face, u - d, v)) / (2 * d);
    jac.col(1) = (chart(face, u, v + d) - chart(face, u, v - d)) / (2 * d);
    const Eigen::Matrix2d hess = hessian(face, u, v);
    const Eigen::Matrix2d metric = jac.transpose() * jac;
    // Smaller root of det(hess - lambda metric) = 0 (2x2 generalised symmetric eigenproblem).
    const double h01 = 0.5 * (hess(0, 1) + hess(1, 0));
    const double qa = metric.determinant();
    const double qb = -(hess(0, 0) * metric(1, 1) + hess(1, 1) * metric(0, 0) - 2.0 * h01 * metric(0, 1));
    const double qc = hess(0, 0) * hess(1, 1) - h01 * h01;
    const double disc = std::max(0.0, qb * qb - 4.0 * qa * qc);
    return (-qb - std::sqrt(disc)) / (2.0 * qa);
  }
  /// Re-expresses a chart position in the chart of the face its direction points to, so that |u|, |v| <= 1
  /// (a chart is smooth beyond its face, but steps in u, v shrink to nothing towards its horizon).
  void rechart(int* face, double* u, double* v) const {
    const Vec3 m = direction(*face, *u, *v);
    Eigen::Index k;
    m.cwiseAbs().maxCoeff(&k);
    *face = 2 * k + (m[k] < 0.0 ? 1 : 0);
    *u = m[(k + 1) % 3] / std::abs(m[k]);
    *v = m[(k + 2) % 3] / std::abs(m[k]);
  }
  void refine(double h, int* face, double* u, double* v) const {
    double fc = f(*face, *u, *v);
    // Pattern search down to 1e-8 in the chart parameters (Newton's basin), then Newton to rounding.
    for (int it = 0; it < 100000 && h > 1e-8; ++it) {
      double bu = *u, bv = *v, bf = fc;
      for (int di = -1; di <= 1; ++di) {
        for (int dj = -1; dj <= 1; ++dj) {
          const double cu = *u + di * h;
          const double cv = *v + dj * h;
          const double cf = f(*face, cu, cv);
          if (cf < bf) {
            bf = cf;
            bu = cu;
            bv = cv;
          }
        }
      }
      if (bf < fc) {
        *u = bu;
        *v = bv;
        rechart(face, u, v);
        fc = f(*face, *u, *v);
      } else {
        h *= 0.5;
      }
    }
    // Newton on the stationarity condition, accepted while the gradient keeps shrinking.
    for (int it = 0; it < 10; ++it) {
      const Eigen::Vector2d g = gradient(*face, *u, *v);
      const Eigen::Vector2d step = hessian(*face, *u, *v).fullPivLu().solve(-g);
      if (!step.allFinite()) break;
      const double nu = *u + step.x();
      const double nv = *v + step.y();
      if (!(gradient(*face, nu, nv).norm() < g.norm())) break;
      *u = nu;
      *v = nv;
    }
  }

  const Ellipsoid& ellipsoid_;
  Vec3 e_;
  Vec3 y_;
  double ea_[3];
  double ya_[3];
};

/// Checks of one closestPoint answer that need no reference: T on the surface, the normal is the unit
/// outward surface normal at T, P - T is along it, and the sign of the distance matches contains().
void expectValidClosestPoint(const Ellipsoid& ellipsoid, const Vec3& p, const Ellipsoid::ClosestPoint& cp) {
  EXPECT_LT(std::abs(ellipsoid.implicitValue(cp.point)), 1e-12)
      << "T not on the surface, P " << p.transpose();
  EXPECT_NEAR(cp.normal.norm(), 1.0, 1e-14);
  EXPECT_LT((cp.normal - ellipsoid.normalAt(cp.point)).norm(), 1e-12);
  EXPECT_GT(cp.normal.dot(cp.point - ellipsoid.center()), 0.0) << "normal not outward";
  const Vec3 pt = p - cp.point;
  EXPECT_NEAR(pt.norm(), std::abs(cp.signed_distance), 1e-15 * (1.0 + pt.norm()));
  // Parallel to 1e-9 relative; the absolute 1e-15 m floor is the rounding of T's coordinates, which
  // dominates the angle for points within ~1e-6 m of the surface.
  EXPECT_LE(pt.cross(cp.normal).norm(), 1e-9 * pt.norm() + 1e-15)
      << "P - T not along the normal, P " << p.transpose() << ", |P - T| " << pt.norm();
  if (ellipsoid.contains(p)) {
    EXPECT_LE(cp.signed_distance, 0.0);
  } else {
    EXPECT_GE(cp.signed_distance, 0.0);
  }
}

/// Compares closestPoint with the brute-force reference (the point only where the reference is unique).
void expectMatchesBruteForce(const Ellipsoid& ellipsoid, const Vec3& p, int* non_unique) {
  const Ellipsoid::ClosestPoint cp = ellipsoid.closestPoint(p);
  const Reference ref = BruteForce(ellipsoid, p).solve();
  expectValidClosestPoint(ellipsoid, p, cp);
  EXPECT_NEAR(std::abs(cp.signed_distance), ref.distance, 1e-9) << "P " << p.transpose();
  if (ref.unique) {
    EXPECT_LT((cp.point - ref.point).norm(), 1e-9)
        << "P " << p.transpose() << " T " << cp.point.transpose() << " ref " << ref.point.transpose();
  } else {
    ++*non_unique;
  }
}

// ------------------------------------------------------------------------------------------------ basics

TEST(EllipsoidTest, DefaultIsUnitSphereAtOrigin) {
  const Ellipsoid e;
  EXPECT_EQ(e.center(), Vec3::Zero());
  EXPECT_EQ(e.radii(), Vec3::Ones());
  EXPECT_EQ(e.rotation(), Mat3::Identity());
  EXPECT_EQ(e.S(), Mat3::Identity());
  EXPECT_EQ(e.Sinv(), Mat3::Identity());
  EXPECT_DOUBLE_EQ(e.implicitValue(Vec3(0.0, 0.6, 0.0)), 0.36 - 1.0);
}

TEST(EllipsoidTest, SphereSpaceMapsAndInsideTest) {
  const Vec3 c(0.1, -0.2, 0.3);
  const Vec3 r(0.5, 0.05, 0.2);
  const Mat3 rot = rotationFromRpy(Vec3(0.3, -0.7, 1.1));
  const Ellipsoid e(c, rot, r);
  // S = R diag(radii); Sinv is its inverse.
  EXPECT_LT((e.S() - rot * r.asDiagonal().toDenseMatrix()).norm(), 1e-15);
  EXPECT_LT((e.S() * e.Sinv() - Mat3::Identity()).norm(), 1e-14);
  // Half way along the first (0.5 m) axis: implicit value 0.5^2 - 1.
  const Vec3 half_axis = c + rot.col(0) * 0.25;
  EXPECT_NEAR(e.implicitValue(half_axis), -0.75, 1e-14);
  EXPECT_TRUE(e.contains(half_axis));
  // Just inside / outside the thin (0.05 m) axis.
  EXPECT_TRUE(e.contains(c + rot.col(1) * 0.0499));
  EXPECT_FALSE(e.contains(c + rot.col(1) * 0.0501));
  EXPECT_FALSE(e.contains(c + rot.col(0) * 0.4 + rot.col(1) * 0.04));  // 0.64 + 0.64 > 1
  EXPECT_LT((e.toSphere(c + rot * Vec3(0.5, -0.05, 0.1)) - Vec3(1.0, -1.0, 0.5)).norm(), 1e-14);
}

TEST(EllipsoidTest, FromRpyUsesRotationFromRpy) {
  const Vec3 rpy(0.2, 0.4, -1.3);
  const Ellipsoid e = Ellipsoid::fromRpy(Vec3(1, 2, 3), rpy, Vec3(0.1, 0.2, 0.3));
  EXPECT_LT((e.rotation() - rotationFromRpy(rpy)).norm(), 1e-15);
  EXPECT_EQ(e.center(), Vec3(1, 2, 3));
  EXPECT_EQ(e.radii(), Vec3(0.1, 0.2, 0.3));
  expectInvalidArgument([] { Ellipsoid::fromRpy(Vec3::Zero(), Vec3(0, kNan, 0), Vec3::Ones()); },
                        {"Ellipsoid::fromRpy(...) : ", "nan"});
}

// ------------------------------------------------------------------------------------------ error paths

TEST(EllipsoidTest, ConstructorRejectsZeroRadius) {
  expectInvalidArgument([] { Ellipsoid(Vec3::Zero(), Mat3::Identity(), Vec3(0.3, 0.0, 0.2)); },
                        {"Ellipsoid::Ellipsoid(...) : ", "radius 1", "got 0"});
}

TEST(EllipsoidTest, ConstructorRejectsNegativeRadius) {
  expectInvalidArgument([] { Ellipsoid(Vec3::Zero(), Mat3::Identity(), Vec3(0.3, 0.2, -0.25)); },
                        {"Ellipsoid::Ellipsoid(...) : ", "radius 2", "-0.25"});
}

TEST(EllipsoidTest, ConstructorRejectsNonFiniteRadius) {
  expectInvalidArgument(
      [] { Ellipsoid(Vec3::Zero(), Mat3::Identity(), Vec3(std::numeric_limits<double>::infinity(), 1, 1)); },
      {"Ellipsoid::Ellipsoid(...) : ", "radius 0", "inf"});
  expectInvalidArgument([] { Ellipsoid(Vec3::Zero(), Mat3::Identity(), Vec3(1, kNan, 1)); },
                        {"Ellipsoid::Ellipsoid(...) : ", "radius 1", "nan"});
}

TEST(EllipsoidTest, ConstructorRejectsNanCentre) {
  expectInvalidArgument([] { Ellipsoid(Vec3(0.5, kNan, 0.0), Mat3::Identity(), Vec3::Ones()); },
                        {"Ellipsoid::Ellipsoid(...) : ", "centre", "(0.5, nan, 0)"});
}

TEST(EllipsoidTest, ConstructorRejectsNonOrthonormalRotation) {
  Mat3 scaled = Mat3::Identity();
  scaled(1, 1) = 1.01;
  expectInvalidArgument([&] { Ellipsoid(Vec3::Zero(), scaled, Vec3::Ones()); },
                        {"Ellipsoid::Ellipsoid(...) : ", "rotation", "1.01"});
  Mat3 sheared = Mat3::Identity();
  sheared(0, 2) = 0.125;
  expectInvalidArgument([&] { Ellipsoid(Vec3::Zero(), sheared, Vec3::Ones()); },
                        {"Ellipsoid::Ellipsoid(...) : ", "rotation", "0.125"});
  // A reflection is orthonormal but has det -1.
  Mat3 reflection = Mat3::Identity();
  reflection(2, 2) = -1.0;
  expectInvalidArgument([&] { Ellipsoid(Vec3::Zero(), reflection, Vec3::Ones()); },
                        {"Ellipsoid::Ellipsoid(...) : ", "det = -1"});
  Mat3 with_nan = Mat3::Identity();
  with_nan(2, 0) = kNan;
  expectInvalidArgument([&] { Ellipsoid(Vec3::Zero(), with_nan, Vec3::Ones()); },
                        {"Ellipsoid::Ellipsoid(...) : ", "rotation", "nan"});
}

TEST(EllipsoidTest, ConstructorAcceptsRotationWithinToleranceAndReorthonormalises) {
  Mat3 rot = rotationFromRpy(Vec3(0.1, 0.2, 0.3));
  rot(0, 1) += 4e-7;
  const Ellipsoid e(Vec3::Zero(), rot, Vec3(0.3, 0.2, 0.1));
  EXPECT_LT((e.rotation().transpose() * e.rotation() - Mat3::Identity()).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_LT((e.rotation() - rot).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_LT((e.S() * e.Sinv() - Mat3::Identity()).norm(), 1e-14);
}

TEST(EllipsoidTest, InflatedRejectsNonPositiveRadius) {
  const Ellipsoid e(Vec3::Zero(), Mat3::Identity(), Vec3(0.5, 0.05, 0.2));
  expectInvalidArgument([&] { e.inflated(-0.06); }, {"Ellipsoid::inflated(...) : ", "-0.06"});
  expectInvalidArgument([&] { e.inflated(-0.05); }, {"Ellipsoid::inflated(...) : ", "-0.05"});
  expectInvalidArgument([&] { e.inflated(kNan); }, {"Ellipsoid::inflated(...) : ", "nan"});
  EXPECT_NO_THROW(e.inflated(-0.049));
}

// ---------------------------------------------------------------------------- inflated / transformed

TEST(EllipsoidTest, InflatedGrowsEveryRadius) {
  const Ellipsoid e = Ellipsoid::fromRpy(Vec3(0.1, 0.2, 0.3), Vec3(0.4, 0.5, 0.6), Vec3(0.5, 0.05, 0.2));
  const Ellipsoid big = e.inflated(0.01);
  EXPECT_LT((big.radii() - Vec3(0.51, 0.06, 0.21)).norm(), 1e-15);
  EXPECT_EQ(big.center(), e.center());
  EXPECT_LT((big.rotation() - e.rotation()).norm(), 1e-15);
  // The tips of the semi-axes move out by exactly the margin; the original lies strictly inside.
  for (int i = 0; i < 3; ++i) {
    const Vec3 tip = e.center() + e.rotation().col(i) * (e.radii()[i] + 0.01);
    EXPECT_NEAR(big.implicitValue(tip), 0.0, 1e-14);
  }
  Rng rng(7);
  for (int k = 0; k < 100; ++k) {
    const Vec3 on_surface = e.center() + e.S() * rng.unitVector();
    EXPECT_TRUE(big.contains(on_surface));
    EXPECT_FALSE(e.inflated(-0.01).contains(on_surface));
  }
  // For a sphere, inflating is offsetting: the distance to the surface drops by the margin.
  const Ellipsoid sphere(Vec3(1, 1, 1), Mat3::Identity(), Vec3::Constant(0.3));
  const Vec3 p(1.5, 1.2, 0.9);
  EXPECT_NEAR(sphere.closestPoint(p).signed_distance - sphere.inflated(0.05).closestPoint(p).signed_distance,
              0.05, 1e-14);
}

TEST(EllipsoidTest, TransformedMovesTheSurfaceRigidly) {
  const Ellipsoid e = Ellipsoid::fromRpy(Vec3(0.1, -0.2, 0.3), Vec3(0.3, -0.7, 1.1), Vec3(0.5, 0.05, 0.2));
  Iso3 pose = Iso3::Identity();
  pose.translate(Vec3(1.0, -2.0, 0.5));
  pose.rotate(Eigen::AngleAxisd(0.9, Vec3(1, 2, -1).normalized()));
  const Ellipsoid moved = e.transformed(pose);
  EXPECT_LT((moved.center() - pose * e.center()).norm(), 1e-15);
  EXPECT_LT((moved.rotation() - pose.linear() * e.rotation()).norm(), 1e-15);
  EXPECT_EQ(moved.radii(), e.radii());
  Rng rng(11);
  for (int k = 0; k < 200; ++k) {
    const Vec3 n = rng.unitVector();
    const Vec3 on_surface = e.center() + e.S() * n;
    EXPECT_NEAR(moved.implicitValue(pose * on_surface), 0.0, 1e-12);
    // Any point keeps its implicit value and its closest point moves with it.
    const Vec3 p = e.center() + e.S() * (n * rng.uniform(0.0, 2.0));
    EXPECT_NEAR(moved.implicitValue(pose * p), e.implicitValue(p), 1e-12);
    const Ellipsoid::ClosestPoint a = e.closestPoint(p);
    const Ellipsoid::ClosestPoint b = moved.closestPoint(pose * p);
    EXPECT_NEAR(a.signed_distance, b.signed_distance, 1e-12);
    EXPECT_LT((pose * a.point - b.point).norm(), 1e-9);
    EXPECT_LT((pose.linear() * a.normal - b.normal).norm(), 1e-9);
  }
}

TEST(EllipsoidTest, TransformedRejectsNonRigidPose) {
  const Ellipsoid e;
  Iso3 pose = Iso3::Identity();
  pose.linear() = Vec3(1.0, 2.0, 1.0).asDiagonal();
  expectInvalidArgument([&] { e.transformed(pose); }, {"Ellipsoid::Ellipsoid(...) : ", "rotation", "2"});
}

// ------------------------------------------------------------------------- normal / radial projection

TEST(EllipsoidTest, NormalAtMatchesGradientOfImplicitFunction) {
  const Ellipsoid e = Ellipsoid::fromRpy(Vec3(0.1, -0.2, 0.3), Vec3(0.3, -0.7, 1.1), Vec3(0.5, 0.05, 0.2));
  Rng rng(3);
  for (int k = 0; k < 100; ++k) {
    const Vec3 p = e.center() + e.S() * (rng.unitVector() * rng.uniform(0.2, 2.0));
    Vec3 grad;
    const double h = 1e-6;
    for (int i = 0; i < 3; ++i) {
      grad[i] = (e.implicitValue(p + h * Vec3::Unit(i)) - e.implicitValue(p - h * Vec3::Unit(i))) / (2 * h);
    }
    EXPECT_LT((e.normalAt(p) - grad.normalized()).norm(), 1e-7);
  }
  // Tip of the 0.05 m axis: the normal is that axis; at the centre the same (documented) choice.
  EXPECT_LT((e.normalAt(e.center() + 0.05 * e.rotation().col(1)) - e.rotation().col(1)).norm(), 1e-14);
  EXPECT_LT((e.normalAt(e.center()) - e.rotation().col(1)).norm(), 1e-15);
}

TEST(EllipsoidTest, RadialProjection) {
  const Ellipsoid e = Ellipsoid::fromRpy(Vec3(0.1, -0.2, 0.3), Vec3(0.3, -0.7, 1.1), Vec3(0.5, 0.05, 0.2));
  const Mat3& r = e.rotation();
  // Along an axis it is the axis tip, from inside or outside.
  EXPECT_LT((e.radialProjection(e.center() + 0.01 * r.col(2)) - (e.center() + 0.2 * r.col(2))).norm(), 1e-15);
  EXPECT_LT((e.radialProjection(e.center() - 3.0 * r.col(0)) - (e.center() - 0.5 * r.col(0))).norm(), 1e-15);
  // Local (0.25, 0.025, 0.1) is (0.5, 0.5, 0.5) in sphere space: projection to (1,1,1)/sqrt(3).
  const Vec3 expected = e.center() + r * Vec3(0.5, 0.05, 0.2) / std::sqrt(3.0);
  EXPECT_LT((e.radialProjection(e.center() + r * Vec3(0.25, 0.025, 0.1)) - expected).norm(), 1e-15);
  // Centre: the +x semi-axis tip (documented choice).
  EXPECT_LT((e.radialProjection(e.center()) - (e.center() + 0.5 * r.col(0))).norm(), 1e-15);
}

// ------------------------------------------------------------------------------------------ closestPoint

TEST(EllipsoidClosestPoint, UnitSphereClosedForm) {
  const Ellipsoid e;
  Rng rng(1);
  for (int k = 0; k < 500; ++k) {
    const Vec3 p = rng.unitVector() * rng.uniform(0.001, 3.0);
    const Ellipsoid::ClosestPoint cp = e.closestPoint(p);
    EXPECT_LT((cp.point - p / p.norm()).norm(), 1e-15);
    EXPECT_NEAR(cp.signed_distance, p.norm() - 1.0, 1e-15);
    EXPECT_LT((cp.normal - p / p.norm()).norm(), 1e-15);
  }
}

TEST(EllipsoidClosestPoint, SphereOfRadiusClosedForm) {
  const Vec3 c(0.4, -1.0, 2.0);
  const double radius = 0.37;
  const Ellipsoid e = Ellipsoid::fromRpy(c, Vec3(0.5, 1.0, -2.0), Vec3::Constant(radius));
  Rng rng(2);
  for (int k = 0; k < 500; ++k) {
    const Vec3 p = c + rng.unitVector() * rng.uniform(0.0001, 2.0);
    const Ellipsoid::ClosestPoint cp = e.closestPoint(p);
    EXPECT_LT((cp.point - (c + radius * (p - c) / (p - c).norm())).norm(), 1e-14);
    EXPECT_NEAR(cp.signed_distance, (p - c).norm() - radius, 1e-14);
    EXPECT_LT((cp.normal - (p - c).normalized()).norm(), 1e-13);
  }
}

TEST(EllipsoidClosestPoint, InsideOnLongAxisClosedForm) {
  // Inside on the long axis of an ellipse (a, b): the closest point is (a^2 x / (a^2 - b^2), +-b sqrt(...))
  // (Lagrange: x_T = a^2 x / (a^2 + t) with t = -b^2) as long as a^2 x / (a^2 - b^2) < a.
  const Ellipsoid e(Vec3::Zero(), Mat3::Identity(), Vec3(0.5, 0.05, 0.2));
  const double x = 0.1;
  const double xt = 0.25 * x / (0.25 - 0.0025);
  const double yt = 0.05 * std::sqrt(1.0 - (xt / 0.5) * (xt / 0.5));
  const Ellipsoid::ClosestPoint cp = e.closestPoint(Vec3(x, 0.0, 0.0));
  EXPECT_NEAR(cp.point.x(), xt, 1e-15);
  EXPECT_NEAR(std::abs(cp.point.y()), yt, 1e-15);
  EXPECT_EQ(cp.point.z(), 0.0);
  EXPECT_NEAR(cp.signed_distance, -std::hypot(xt - x, yt), 1e-15);
  // Beyond the evolute (a^2 x / (a^2 - b^2) >= a) the closest point is the tip of the axis.
  const Ellipsoid::ClosestPoint tip = e.closestPoint(Vec3(0.499, 0.0, 0.0));
  EXPECT_LT((tip.point - Vec3(0.5, 0, 0)).norm(), 1e-15);
  EXPECT_NEAR(tip.signed_distance, -0.001, 1e-15);
}

TEST(EllipsoidClosestPoint, CentreGoesAlongTheSmallestAxis) {
  const Ellipsoid e = Ellipsoid::fromRpy(Vec3(0.1, -0.2, 0.3), Vec3(0.3, -0.7, 1.1), Vec3(0.5, 0.05, 0.2));
  const Ellipsoid::ClosestPoint cp = e.closestPoint(e.center());
  EXPECT_NEAR(cp.signed_distance, -0.05, 1e-15);
  EXPECT_LT(std::abs(std::abs((cp.point - e.center()).dot(e.rotation().col(1))) - 0.05), 1e-15);
  expectValidClosestPoint(e, e.center(), cp);
  // Slightly off the centre (10:1 ellipsoid, 1e-9 m) the answer is on the near side of the thin axis.
  const Vec3 p = e.center() + e.rotation() * Vec3(3e-9, -1e-9, 2e-9);
  const Ellipsoid::ClosestPoint near = e.closestPoint(p);
  EXPECT_LT((near.point - (e.center() - 0.05 * e.rotation().col(1))).norm(), 1e-8);
  int non_unique = 0;
  expectMatchesBruteForce(e, p, &non_unique);
  EXPECT_EQ(non_unique, 0);
}

TEST(EllipsoidClosestPoint, ExactZeroCoordinatesMatchBruteForce) {
  // Unrotated, so the local coordinates are exactly zero: Eberly's special cases.
  const std::vector<Vec3> radii_set = {Vec3(0.5, 0.05, 0.2), Vec3(0.05, 0.2, 0.5), Vec3(0.3, 0.3, 0.03),
                                       Vec3(0.5, 0.05, 0.05)};
  const std::vector<double> values = {0.0, 0.01, -0.04, 0.15, 0.3, -0.6, 1.0};
  int count = 0;
  int non_unique = 0;
  for (const Vec3& r : radii_set) {
    const Ellipsoid e(Vec3::Zero(), Mat3::Identity(), r);
    for (double x : values) {
      for (double y : values) {
        for (double z : values) {
          const int zeros = (x == 0.0) + (y == 0.0) + (z == 0.0);
          if (zeros == 0) continue;
          expectMatchesBruteForce(e, Vec3(x, y, z), &non_unique);
          ++count;
        }
      }
    }
  }
  EXPECT_GT(count, 400);
  EXPECT_LT(non_unique, count / 4);  // most are unique, so points are compared too
}

struct RandomCase {
  const char* name;
  Vec3 center;
  Vec3 rpy;
  Vec3 radii;
};

class EllipsoidClosestPointRandom : public ::testing::TestWithParam<RandomCase> {};

TEST_P(EllipsoidClosestPointRandom, MatchesBruteForce) {
  const RandomCase& param = GetParam();
  const Ellipsoid e = Ellipsoid::fromRpy(param.center, param.rpy, param.radii);
  Rng rng(12345);
  std::vector<Vec3> sphere_points;  // in sphere space
  for (int k = 0; k < 60; ++k) sphere_points.push_back(rng.unitVector() * rng.uniform(1.0, 3.0));
  for (int k = 0; k < 10; ++k) sphere_points.push_back(rng.unitVector() * rng.uniform(3.0, 30.0));
  for (int k = 0; k < 80; ++k) sphere_points.push_back(rng.unitVector() * std::cbrt(rng.uniform(0.0, 1.0)));
  for (int k = 0; k < 20; ++k) sphere_points.push_back(rng.unitVector() * rng.uniform(0.0, 0.02));
  for (int k = 0; k < 20; ++k) {
    sphere_points.push_back(rng.unitVector() *
                            (1.0 + (k % 2 ? 1 : -1) * std::pow(10.0, rng.uniform(-9, -5))));
  }
  // Close to the symmetry planes and axes (one or two local coordinates 1e-13 .. 1e-7 of the radius).
  for (int k = 0; k < 40; ++k) {
    Vec3 q = rng.unitVector() * rng.uniform(0.0, 2.0);
    const int axis = k % 3;
    q[axis] = (k % 2 ? 1 : -1) * std::pow(10.0, rng.uniform(-13, -7));
    if (k % 4 == 0) q[(axis + 1) % 3] = std::pow(10.0, rng.uniform(-13, -7));
    sphere_points.push_back(q);
  }
  int inside = 0;
  int non_unique = 0;
  for (const Vec3& q : sphere_points) {
    const Vec3 p = e.center() + e.S() * q;
    inside += e.contains(p);
    expectMatchesBruteForce(e, p, &non_unique);
  }
  EXPECT_GT(inside, 80);
  EXPECT_GT(static_cast<int>(sphere_points.size()) - inside, 80);
  // Only the deliberate near-ties (tiny coordinate along the thinnest axis) skip the point comparison.
  EXPECT_LE(non_unique, 25);
}

INSTANTIATE_TEST_SUITE_P(
    Ratios, EllipsoidClosestPointRandom,
    ::testing::Values(RandomCase{"Thin10to1", Vec3(0.1, -0.2, 0.3), Vec3(0.3, -0.7, 1.1),
                                 Vec3(0.5, 0.05, 0.2)},
                      RandomCase{"Flat10to1", Vec3(-1, 0, 2), Vec3(-1.2, 0.4, 2.5), Vec3(0.02, 0.2, 0.1)},
                      RandomCase{"Oblate", Vec3(0, 0, 1), Vec3(0.1, 0.2, 0.3), Vec3(0.3, 0.3, 0.03)},
                      RandomCase{"Prolate", Vec3(0.3, 0.3, 0.3), Vec3(2.0, -0.5, 0.7), Vec3(0.05, 0.5, 0.05)},
                      RandomCase{"Head", Vec3(0, 0, 1.6), Vec3(0.0, 0.1, 0.0), Vec3(0.09, 0.075, 0.115)}),
    [](const ::testing::TestParamInfo<RandomCase>& param_info) {
      return std::string(param_info.param.name);
    });

// ---------------------------------------------------------------------------------------------- firstHit

TEST(EllipsoidFirstHit, FastPointCrossingThinEllipsoidIsDetected) {
  // 50 m/s for one 1/240 s substep crosses the 0.02 m thick slab completely.
  const Vec3 c(0.2, -0.1, 1.0);
  const Ellipsoid thin(c, Mat3::Identity(), Vec3(0.3, 0.3, 0.01));
  const Vec3 a = c + Vec3(0.05, -0.02, 0.1);
  const Vec3 b = a + Vec3(0.0, 0.0, -50.0 / 240.0);
  ASSERT_FALSE(thin.contains(a));
  ASSERT_FALSE(thin.contains(b));  // a per-position inside test would miss it
  double t = -1.0;
  ASSERT_TRUE(thin.firstHit(a, b, &t));
  const double z_surface = 0.01 * std::sqrt(1.0 - (0.05 * 0.05 + 0.02 * 0.02) / 0.09);
  EXPECT_NEAR(t, (0.1 - z_surface) / (50.0 / 240.0), 1e-14);
  EXPECT_NEAR(thin.implicitValue(a + t * (b - a)), 0.0, 1e-12);
  // The same crossing of a tilted copy, along its thin axis.
  const Ellipsoid tilted = Ellipsoid::fromRpy(c, Vec3(0.7, -0.4, 2.0), Vec3(0.3, 0.3, 0.01));
  const Vec3 axis = tilted.rotation().col(2);
  const Vec3 a2 = c + tilted.rotation() * Vec3(0.05, -0.02, 0.1);
  const Vec3 b2 = a2 - axis * (50.0 / 240.0);
  ASSERT_FALSE(tilted.contains(a2));
  ASSERT_FALSE(tilted.contains(b2));
  ASSERT_TRUE(tilted.firstHit(a2, b2, &t));
  EXPECT_NEAR(t, (0.1 - z_surface) / (50.0 / 240.0), 1e-12);
  // And in the opposite direction it enters through the other face.
  ASSERT_TRUE(thin.firstHit(b, a, &t));
  EXPECT_NEAR(t, (50.0 / 240.0 - 0.1 - z_surface) / (50.0 / 240.0), 1e-14);
}

TEST(EllipsoidFirstHit, SphereEntryParameterIsAnalytic) {
  const Vec3 c(1, 2, 3);
  const Ellipsoid sphere = Ellipsoid::fromRpy(c, Vec3(0.3, 0.2, 0.1), Vec3::Constant(0.5));
  // Line at distance 0.3 from the centre: entry at x = -0.4 of [-2, 2] -> t = 1.6 / 4 = 0.4.
  double t = -1.0;
  ASSERT_TRUE(sphere.firstHit(c + Vec3(-2, 0.3, 0), c + Vec3(2, 0.3, 0), &t));
  EXPECT_NEAR(t, 0.4, 1e-15);
  // Through the centre, diagonal: entry at distance |a - c| - r along the path.
  const Vec3 a = c + Vec3(1, -2, 2);  // |a - c| = 3
  ASSERT_TRUE(sphere.firstHit(a, c - Vec3(1, -2, 2), &t));
  EXPECT_NEAR(t, (3.0 - 0.5) / 6.0, 1e-15);
  // Ending exactly... just past the surface still hits, ending just short misses.
  const Vec3 dir = Vec3(1, -2, 2) / 3.0;
  EXPECT_TRUE(sphere.firstHit(a, c + dir * (0.5 - 1e-9), &t));
  EXPECT_NEAR(t, 1.0, 1e-8);
  EXPECT_FALSE(sphere.firstHit(a, c + dir * (0.5 + 1e-9), &t));
  // A null output pointer is allowed.
  EXPECT_TRUE(sphere.firstHit(a, c, nullptr));
}

TEST(EllipsoidFirstHit, MissesReturnFalse) {
  const Ellipsoid thin(Vec3::Zero(), Mat3::Identity(), Vec3(0.3, 0.3, 0.01));
  double t = -7.0;
  // Passing beside the rim.
  EXPECT_FALSE(thin.firstHit(Vec3(0.31, 0.0, 0.1), Vec3(0.31, 0.0, -0.1), &t));
  // Passing just above the slab (z = 0.0101 at its centre).
  EXPECT_FALSE(thin.firstHit(Vec3(-1.0, 0.0, 0.0101), Vec3(1.0, 0.0, 0.0101), &t));
  EXPECT_TRUE(thin.firstHit(Vec3(-1.0, 0.0, 0.0099), Vec3(1.0, 0.0, 0.0099), &t));
  t = -7.0;
  // Heading for it but stopping short of the surface.
  EXPECT_FALSE(thin.firstHit(Vec3(0.0, 0.0, 0.1), Vec3(0.0, 0.0, 0.0100001), &t));
  // Moving away from it (the line hits it behind the start).
  EXPECT_FALSE(thin.firstHit(Vec3(0.0, 0.0, 0.1), Vec3(0.0, 0.0, 0.2), &t));
  // Not moving, outside.
  EXPECT_FALSE(thin.firstHit(Vec3(0.0, 0.0, 0.1), Vec3(0.0, 0.0, 0.1), &t));
  EXPECT_EQ(t, -7.0);  // untouched on a miss
}

TEST(EllipsoidFirstHit, StartInsideReturnsZero) {
  const Ellipsoid e = Ellipsoid::fromRpy(Vec3(0.1, -0.2, 0.3), Vec3(0.3, -0.7, 1.1), Vec3(0.5, 0.05, 0.2));
  const Vec3 inside = e.center() + e.S() * Vec3(0.3, -0.6, 0.2);
  ASSERT_TRUE(e.contains(inside));
  double t = -1.0;
  EXPECT_TRUE(e.firstHit(inside, inside + Vec3(3, 0, 0), &t));
  EXPECT_EQ(t, 0.0);
  t = -1.0;
  EXPECT_TRUE(e.firstHit(inside, inside, &t));  // not moving
  EXPECT_EQ(t, 0.0);
  // Starting exactly on the surface and moving inwards enters at t = 0; moving outwards does not enter.
  const Ellipsoid unit;
  EXPECT_TRUE(unit.firstHit(Vec3(1, 0, 0), Vec3(0.5, 0.1, 0), &t));
  EXPECT_EQ(t, 0.0);
  EXPECT_FALSE(unit.firstHit(Vec3(1, 0, 0), Vec3(1.5, 0.1, 0), &t));
}

// ------------------------------------------------------------------------------------------ reactionForce

TEST(ReactionForce, HandComputedExample) {
  // N points into the body (here -z: the body is below). F = (1, 2, 3): unconstrained part (1, 2, 0);
  // V.N = 2 (moving into the body at 2 m/s); constrained = -(1000 * 0.01 + 5 * 2) N = (0, 0, 20).
  const Vec3 out = reactionForce(Vec3(1, 2, 3), Vec3(0, 0, -1), 0.01, Vec3(0.5, 0, -2), 1000.0, 5.0);
  EXPECT_LT((out - Vec3(1, 2, 20)).norm(), 1e-13);
}

TEST(ReactionForce, NormalAndTangentialComponents) {
  Rng rng(5);
  for (int k = 0; k < 200; ++k) {
    const Vec3 f(rng.uniform(-10, 10), rng.uniform(-10, 10), rng.uniform(-10, 10));
    const Vec3 n = rng.unitVector();
    const Vec3 v(rng.uniform(-3, 3), rng.uniform(-3, 3), rng.uniform(-3, 3));
    const double depth = rng.uniform(0.0, 0.05);
    const double kk = rng.uniform(100, 5000);
    const double c = rng.uniform(0, 50);
    const Vec3 out = reactionForce(f, n, depth, v, kk, c);
    const double expected_normal = -(kk * depth + c * v.dot(n));
    const double scale = f.norm() + std::abs(kk * depth) + std::abs(c * v.dot(n));
    EXPECT_NEAR(out.dot(n), expected_normal, 1e-12 * scale);
    const Vec3 tangential_out = out - out.dot(n) * n;
    const Vec3 tangential_in = f - f.dot(n) * n;
    EXPECT_LT((tangential_out - tangential_in).norm(), 1e-12 * scale);
  }
}

// A head pose from tf whose quaternion is off unit norm by 2.8e-7 (the fuzz_messages crasher
// test/fuzz_corpus/messages/crash_quaternion_norm_off_3e-7): its matrix is 1.1e-6 off orthonormal, just
// outside the constructor's 1e-6. transformed() takes the nearest rotation; a pose 1 % off still throws.
TEST(EllipsoidTest, TransformedTakesANearlyUnitQuaternionAsItsRotation) {
  const Ellipsoid body(Vec3(0.0, 0.19, -0.24), Mat3::Identity(), Vec3(0.07, 0.09, 0.055));
  Iso3 pose = Iso3::Identity();  // the crasher's head rotation, as tf2::transformToEigen made it
  pose.linear() = Vec3(0.9999994368216198, 0.9999994368216198, 1.0).asDiagonal();
  pose.translation() = Vec3(0.0, 0.0, 1.6);
  const Ellipsoid moved = body.transformed(pose);
  EXPECT_LT((moved.rotation() - Mat3::Identity()).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LT((moved.center() - Vec3(0.0, 0.19, 1.36)).norm(), 1e-6);  // translation kept, rotation ~ I
  // A turned pose: the result is a rotation (to rounding) within |q|^2 - 1 = 5.6e-7 of the normalised
  // quaternion's (the nearest rotation to the unnormalised matrix differs from it by that order).
  const double a = 1.4;  // a half-turn-ish yaw: the matrix is 2.2e-6 off orthonormal
  pose.linear() = Quat(0.99999972 * std::cos(a), 0.0, 0.0, 0.99999972 * std::sin(a)).toRotationMatrix();
  const Mat3 r = body.transformed(pose).rotation();
  const Mat3 expected = Eigen::AngleAxisd(2.0 * a, Vec3::UnitZ()).toRotationMatrix();
  EXPECT_LT((r.transpose() * r - Mat3::Identity()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((r - expected).cwiseAbs().maxCoeff(), 6e-7);
  pose.linear() = 1.01 * Mat3::Identity();
  EXPECT_THROW(body.transformed(pose), std::invalid_argument);
}

}  // namespace
}  // namespace hair_sim
