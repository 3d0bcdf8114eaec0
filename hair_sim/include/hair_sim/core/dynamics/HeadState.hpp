#pragma once
/// The head's pose and its time derivatives, all in the world frame, at one substep.
#include <limits>

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
  /// The state at the next substep (dt > 0 after it). A jump farther than the teleport limits from the
  /// previous pose is a teleport: the head is at rest at the new pose (no velocity or acceleration from
  /// the jump), and teleported() says so until the next update.
  HeadState update(const Iso3& pose, double dt);
  const HeadState& state() const { return state_; }

  /// Teleport limits: a move of more than `distance` (m) or a turn of more than `angle` (rad) within one
  /// substep (both > 0; infinity = never, the default). Throws std::invalid_argument otherwise.
  void setTeleportLimits(double distance, double angle);
  /// Was the last update a teleport? Then jump() gives its distance (m) and angle (rad).
  bool teleported() const { return teleported_; }
  double jumpDistance() const { return jump_distance_; }
  double jumpAngle() const { return jump_angle_; }

 private:
  HeadState state_;
  double tau_ = 0.0;
  double teleport_distance_ = std::numeric_limits<double>::infinity();
  double teleport_angle_ = std::numeric_limits<double>::infinity();
  bool teleported_ = false;
  double jump_distance_ = 0.0, jump_angle_ = 0.0;
};

}  // namespace hair_sim
