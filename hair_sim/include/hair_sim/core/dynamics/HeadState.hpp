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
class HeadMotionEstimator {
 public:
  /// Head at rest at this pose.
  void reset(const Iso3& pose);
  /// The state at the next substep (dt > 0 after it).
  HeadState update(const Iso3& pose, double dt);
  const HeadState& state() const { return state_; }

 private:
  HeadState state_;
};

}  // namespace hair_sim
