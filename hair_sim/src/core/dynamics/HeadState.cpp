#include "hair_sim/core/dynamics/HeadState.hpp"

#include <stdexcept>
#include <string>

namespace hair_sim {

void HeadMotionEstimator::reset(const Iso3& pose) {
  state_ = HeadState{};
  state_.pose = pose;
}

void HeadMotionEstimator::setTeleportLimits(double distance, double angle) {
  if (!(distance > 0.0) || !(angle > 0.0))
    throw std::invalid_argument("HeadMotionEstimator::setTeleportLimits: distance " +
                                std::to_string(distance) + " m and angle " + std::to_string(angle) +
                                " rad must be > 0");
  teleport_distance_ = distance;
  teleport_angle_ = angle;
}

HeadState HeadMotionEstimator::update(const Iso3& pose, double dt) {
  jump_distance_ = (pose.translation() - state_.pose.translation()).norm();
  jump_angle_ = Eigen::AngleAxisd(state_.pose.linear().transpose() * pose.linear()).angle();
  teleported_ = jump_distance_ > teleport_distance_ || jump_angle_ > teleport_angle_;
  if (teleported_) {
    reset(pose);
    return state_;
  }
  HeadState next;
  next.pose = pose;
  const double k = tau_ > 0.0 ? dt / (tau_ + dt) : 1.0;  // first-order low-pass gain
  const Vec3 v = (pose.translation() - state_.pose.translation()) / dt;
  next.linear_velocity = state_.linear_velocity + k * (v - state_.linear_velocity);
  const Vec3 a = (next.linear_velocity - state_.linear_velocity) / dt;
  next.linear_acceleration = state_.linear_acceleration + k * (a - state_.linear_acceleration);
  const Mat3 relative = state_.pose.linear().transpose() * pose.linear();  // in the previous head frame
  const Eigen::AngleAxisd aa(relative);
  const Vec3 w = state_.pose.linear() * (aa.axis() * aa.angle() / dt);
  next.angular_velocity = state_.angular_velocity + k * (w - state_.angular_velocity);
  const Vec3 alpha = (next.angular_velocity - state_.angular_velocity) / dt;
  next.angular_acceleration = state_.angular_acceleration + k * (alpha - state_.angular_acceleration);
  state_ = next;
  return next;
}

}  // namespace hair_sim
