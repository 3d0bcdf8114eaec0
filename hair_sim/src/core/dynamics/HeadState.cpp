#include "hair_sim/core/dynamics/HeadState.hpp"

namespace hair_sim {

void HeadMotionEstimator::reset(const Iso3& pose) {
  state_ = HeadState{};
  state_.pose = pose;
}

HeadState HeadMotionEstimator::update(const Iso3& pose, double dt) {
  HeadState next;
  next.pose = pose;
  next.linear_velocity = (pose.translation() - state_.pose.translation()) / dt;
  next.linear_acceleration = (next.linear_velocity - state_.linear_velocity) / dt;
  const Mat3 relative = state_.pose.linear().transpose() * pose.linear();  // in the previous head frame
  const Eigen::AngleAxisd aa(relative);
  const Vec3 body_rate = aa.axis() * aa.angle() / dt;
  next.angular_velocity = state_.pose.linear() * body_rate;
  next.angular_acceleration = (next.angular_velocity - state_.angular_velocity) / dt;
  state_ = next;
  return next;
}

}  // namespace hair_sim
