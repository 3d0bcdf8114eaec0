#pragma once
/// Collision body of the paper's section 4.3a: an ellipsoid given by centre e0, orientation and radii.
/// S maps the unit sphere onto the ellipsoid (S = R diag(radii)); S^-1 is precomputed so that the
/// inside test and the path (ray) test run in sphere space.
#include "hair_sim/core/TypeDefs.hpp"

namespace hair_sim {

class Ellipsoid {
 public:
  /// Nearest surface point T of a query point P, with the outward unit normal N at T.
  struct ClosestPoint {
    Vec3 point = Vec3::Zero();
    Vec3 normal = Vec3::UnitZ();
    /// Euclidean |P - T|, negative when P is inside.
    double signed_distance = 0.0;
  };

  /// Unit sphere at the origin.
  Ellipsoid();
  /// Throws std::invalid_argument (prefix "Ellipsoid::Ellipsoid(...) : ") when a radius is not finite
  /// and > 0, the centre is not finite, or the rotation is not orthonormal with det +1 (tolerance 1e-6).
  Ellipsoid(const Vec3& center, const Mat3& rotation, const Vec3& radii);
  /// Same, orientation from roll, pitch, yaw (rad, see rotationFromRpy).
  static Ellipsoid fromRpy(const Vec3& center, const Vec3& rpy, const Vec3& radii);

  const Vec3& center() const { return center_; }
  const Mat3& rotation() const { return rotation_; }
  const Vec3& radii() const { return radii_; }
  /// x_world = center + S * x_sphere.
  const Mat3& S() const { return S_; }
  /// x_sphere = Sinv * (x_world - center).
  const Mat3& Sinv() const { return Sinv_; }

  /// The same ellipsoid with every radius grown by margin (m, may be negative while radii stay > 0).
  Ellipsoid inflated(double margin) const;
  /// The ellipsoid moved rigidly: centre and orientation composed with pose (pose * this). A pose whose
  /// rotation is orthonormal within 1e-4 (a tf quaternion slightly off unit norm) counts as the nearest
  /// rotation; one further off throws std::invalid_argument.
  Ellipsoid transformed(const Iso3& pose) const;

  /// Point in sphere space.
  Vec3 toSphere(const Vec3& p) const { return Sinv_ * (p - center_); }
  /// |S^-1 (p - e0)|^2 - 1: negative inside, zero on the surface, positive outside.
  double implicitValue(const Vec3& p) const { return toSphere(p).squaredNorm() - 1.0; }
  /// Strictly inside (implicitValue < 0).
  bool contains(const Vec3& p) const { return implicitValue(p) < 0.0; }
  /// Outward unit normal of the level set through p (p need not be on the surface; p != centre).
  Vec3 normalAt(const Vec3& p) const;
  /// The surface point on the ray from the centre through p (radial projection in sphere space).
  Vec3 radialProjection(const Vec3& p) const;
  /// True Euclidean closest surface point, from inside or outside, robust up to large axis ratios
  /// (Eberly's set-up, Newton on the Lagrange multiplier with a bisection fallback), accurate to ~1e-12
  /// relative.
  ClosestPoint closestPoint(const Vec3& p) const;
  /// Path test (the paper's ray test in sphere space): if the straight path a -> b enters the
  /// ellipsoid, returns true with *t_enter in [0, 1] the first parameter on the surface
  /// (a + t (b - a)). A path starting inside returns true with *t_enter = 0.
  bool firstHit(const Vec3& a, const Vec3& b, double* t_enter) const;

 private:
  Vec3 center_;
  Mat3 rotation_;
  Vec3 radii_;
  Mat3 S_;
  Mat3 Sinv_;
};

/// Reaction constraint, paper equations (8)-(10):
///   F_out = F_in - (F_in . N) N - (k |PT| + c V . N) N
/// F_in: applied force at P (N); normal: unit N at T pointing INTO the body (the paper's convention:
/// with it the constrained term -(k |PT| + c V.N) N pushes P out and damps its inward speed);
/// depth: |PT| (m, >= 0); velocity: V of P (m/s); k: constraint strength (N/m); c: damping (N s/m).
Vec3 reactionForce(const Vec3& f_in, const Vec3& normal, double depth, const Vec3& velocity, double k,
                   double c);

}  // namespace hair_sim
