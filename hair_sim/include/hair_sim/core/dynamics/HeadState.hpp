#pragma once
/// The head's pose and its time derivatives, all in the world frame, at one substep.
#include "hair_sim/core/TypeDefs.hpp"

namespace hair_sim {

struct HeadState {
  Iso3 pose = Iso3::Identity();              ///< head frame in the world frame
  Vec3 linear_velocity = Vec3::Zero();       ///< of the head frame origin (m/s)
  Vec3 linear_acceleration = Vec3::Zero();   ///< (m/s^2)
  Vec3 angular_velocity = Vec3::Zero();      ///< (rad/s)
  Vec3 angular_acceleration = Vec3::Zero();  ///< (rad/s^2)
};

/// Velocities and accelerations of the head from its poses at consecutive substeps, by backward
/// differences: v_n = (p_n - p_{n-1}) / dt, a_n = (v_n - v_{n-1}) / dt; the angular velocity from the
/// rotation log(R_{n-1}^T R_n) / dt (exact for constant spin, no Euler angles, no pole).
///
/// Poses sampled from a tf buffer are linear between tf messages, so raw second differences spike
/// at every message; a smoothing time constant tau > 0 low-pass filters velocity and acceleration
/// (first order, y += dt / (tau + dt) (x - y)). tau = 0 (the offline runner's smooth scenario curves)
/// uses the raw differences.
class HeadMotionEstimator {
 public:
  /// tau: smoothing time constant (s, >= 0).
  explicit HeadMotionEstimator(double smoothing_time = 0.0) : tau_(smoothing_time) {}
  /// Head at rest at this pose.
  void reset(const Iso3& pose);
  /// The state at the next substep (dt > 0 after it).
  HeadState update(const Iso3& pose, double dt);
  const HeadState& state() const { return state_; }

 private:
  HeadState state_;
  double tau_ = 0.0;
};

}  // namespace hair_sim
