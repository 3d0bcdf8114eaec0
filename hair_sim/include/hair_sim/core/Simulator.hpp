#pragma once
/// The substep loop (paper 4.1): every column of control points of every strip is a chain of rigid
/// segments (Fig. 2c) solved from the root down with the angular dynamics (1)-(7).
///
/// Angles. The paper's theta and phi are polar angles; here each segment's two angles are measured
/// about the two axes perpendicular to the segment in a frame that travels with it, so the working
/// point is always at the origin of its own chart and no orientation reaches a pole. Equation (7)
/// (corrected, see DESIGN.md) then reads, with w^n the rotation vector from the direction at step
/// n-1 to the one at step n:
///     I (w^{n+1} - w^n) + gamma dt w^n = dt^2 M,   M = M_spring + M_external     (2)
///     M_external = (d/2) n x F                       (4),(5): u F_theta, v F_phi with u = d/2
///     M_spring   = -k (angle from the rest direction) about the axis rest x n     (3)
///     F          = rho d (g + a) + d f               (6), a fictitious, f = air_drag (v_air - v_hair)
///     I          = rho d^3 / 3
/// The rest direction of a segment is its styled direction carried by the rotation of its parent
/// (relative to the parent segment, the hinge); the first segment's is fixed in the head frame.
/// Rest directions are compensated so that the styled shape is the equilibrium under gravity at the
/// rest head pose.
#include <vector>

#include "hair_sim/core/dynamics/HeadState.hpp"
#include "hair_sim/core/model/Hairstyle.hpp"
#include "hair_sim/core/model/PhysicsParameters.hpp"

namespace hair_sim {

/// Everything the world contributes to one substep.
struct StepInputs {
  HeadState head;
  Vec3 wind = Vec3::Zero();  ///< air velocity, world frame (m/s)
};

class Simulator {
 public:
  /// Throws std::invalid_argument on invalid parameters or hairstyle.
  Simulator(Hairstyle hairstyle, PhysicsParameters parameters);

  /// Back to the styled rest shape, still.
  void reset();
  /// Puts the hair in the given shape (head frame, positionsHead() order), at rest. Segment lengths
  /// are kept: each segment takes the direction toward its given end point. Roots stay on the scalp.
  /// Throws std::invalid_argument on a wrong size or a non-finite point.
  void setShape(const std::vector<Vec3>& positions_head);
  /// One substep of parameters().substep seconds with the given inputs at its end time.
  void step(const StepInputs& inputs);

  const Hairstyle& hairstyle() const { return hairstyle_; }
  const PhysicsParameters& parameters() const { return params_; }
  long stepCount() const { return steps_; }
  int controlPointCount() const { return static_cast<int>(positions_.size()); }
  /// All control points, head frame, strip by strip, each row-major (the hairstyle's order).
  const std::vector<Vec3>& positionsHead() const { return positions_; }
  /// First index of each strip in positionsHead().
  const std::vector<int>& stripOffsets() const { return strip_offset_; }
  /// Control points in the world frame for the given head pose.
  void positionsWorld(const Iso3& head_pose, std::vector<Vec3>& out) const;
  /// Effective moment of inertia used for the segment ending at point k (>= rho d^3/3; see inertiaFloor).
  double inertia(int k) const { return 1.0 / inv_inertia_[static_cast<std::size_t>(k)]; }
  /// Largest angular rate any segment had relative to the head in the last substep (rad/s).
  double maxSegmentRate() const { return max_rate_; }

  /// Smallest moment of inertia that keeps the explicit scheme (7) stable with margin for this
  /// stiffness and damping: gamma dt / I <= 1 and k dt^2 / I <= 0.5 (omega dt <= 0.71).
  static double inertiaFloor(double stiffness, double damping, double dt);

 private:
  void buildChains();

  Hairstyle hairstyle_;
  PhysicsParameters params_;
  long steps_ = 0;
  double max_rate_ = 0.0;
  std::vector<int> strip_offset_;
  // Per control point k (the segment that ends at k for rows >= 1), head frame.
  std::vector<Vec3> positions_;
  std::vector<Vec3> previous_mid_;   ///< segment midpoint at the end of the last substep
  std::vector<Vec3> velocity_;       ///< midpoint velocity relative to the head over the last substep
  std::vector<Vec3> direction_;      ///< unit segment direction n
  std::vector<Vec3> rate_;           ///< w: rotation vector of the last substep (rad)
  std::vector<Vec3> styled_dir_;     ///< styled direction (head frame)
  std::vector<Vec3> rest_dir_;       ///< compensated rest direction at the styled pose (head frame)
  std::vector<double> length_;       ///< d
  std::vector<double> inv_inertia_;  ///< 1 / I
};

/// Rotation vector that turns unit a onto unit b (axis a x b, angle in [0, pi]); a deterministic
/// perpendicular axis when they are opposite.
Vec3 rotationVectorBetween(const Vec3& a, const Vec3& b);
/// Rotates v by the rotation vector w (Rodrigues).
Vec3 rotateByVector(const Vec3& w, const Vec3& v);
/// Smallest rotation taking unit a onto unit b (a deterministic 180 degree turn when opposite).
Mat3 minimalRotation(const Vec3& a, const Vec3& b);

}  // namespace hair_sim
