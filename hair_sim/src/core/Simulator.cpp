#include "hair_sim/core/Simulator.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace hair_sim {

namespace {

Vec3 anyPerpendicular(const Vec3& a) {
  const Vec3 helper = std::abs(a.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  return a.cross(helper).normalized();
}

}  // namespace

Vec3 rotationVectorBetween(const Vec3& a, const Vec3& b) {
  const Vec3 axis = a.cross(b);
  const double s = axis.norm();
  const double c = a.dot(b);
  const double angle = std::atan2(s, c);
  if (s > 1e-12) return axis * (angle / s);
  if (c > 0.0) return Vec3::Zero();
  return anyPerpendicular(a) * angle;
}

Vec3 rotateByVector(const Vec3& w, const Vec3& v) {
  const double angle = w.norm();
  if (angle < 1e-12) return v + w.cross(v);
  const Vec3 k = w / angle;
  const double c = std::cos(angle);
  const double s = std::sin(angle);
  return v * c + k.cross(v) * s + k * (k.dot(v) * (1.0 - c));
}

Mat3 minimalRotation(const Vec3& a, const Vec3& b) {
  const double c = a.dot(b);
  if (c < -1.0 + 1e-9) {
    const Vec3 k = anyPerpendicular(a);
    return 2.0 * k * k.transpose() - Mat3::Identity();
  }
  const Vec3 v = a.cross(b);
  Mat3 vx;
  vx << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return Mat3::Identity() + vx + vx * vx / (1.0 + c);
}

double Simulator::inertiaFloor(double stiffness, double damping, double dt) {
  return std::max(damping * dt, 2.0 * stiffness * dt * dt);
}

Simulator::Simulator(Hairstyle hairstyle, PhysicsParameters parameters)
    : hairstyle_(std::move(hairstyle)), params_(std::move(parameters)) {
  params_.validate();
  hairstyle_.validate("Simulator::Simulator(...) : hairstyle");
  buildChains();
  reset();
}

void Simulator::buildChains() {
  const int n = hairstyle_.controlPointCount();
  const std::size_t sn = static_cast<std::size_t>(n);
  positions_.assign(sn, Vec3::Zero());
  previous_mid_.assign(sn, Vec3::Zero());
  velocity_.assign(sn, Vec3::Zero());
  direction_.assign(sn, Vec3::UnitZ());
  rate_.assign(sn, Vec3::Zero());
  styled_dir_.assign(sn, Vec3::UnitZ());
  rest_dir_.assign(sn, Vec3::UnitZ());
  length_.assign(sn, 0.0);
  inv_inertia_.assign(sn, 0.0);
  strip_offset_.clear();
  const double dt = params_.substep;
  const double k = params_.hinge_stiffness;
  const double floor = inertiaFloor(k, params_.hinge_damping, dt);
  int offset = 0;
  for (const Strip& s : hairstyle_.strips) {
    strip_offset_.push_back(offset);
    for (int r = 1; r < s.rows; ++r) {
      for (int c = 0; c < s.columns; ++c) {
        const std::size_t i = static_cast<std::size_t>(offset + s.index(r, c));
        const Vec3 seg = s.point(r, c) - s.point(r - 1, c);
        const double d = seg.norm();
        length_[i] = d;
        styled_dir_[i] = seg / d;
        const double inertia = params_.linear_density * d * d * d / 3.0;
        inv_inertia_[i] = 1.0 / std::max(inertia, floor);
        // Compensation: the hinge is pre-bent so that at the styled direction its torque cancels the
        // torque of gravity: rest = exp(-tau_g / k) styled, tau_g = (d/2) n x (rho d g).
        Vec3 rest = styled_dir_[i];
        if (params_.compensate_rest_angles && k > 0.0) {
          const Vec3 tau_g = 0.5 * d * styled_dir_[i].cross(params_.linear_density * d * params_.gravity);
          rest = rotateByVector(-tau_g / k, styled_dir_[i]);
        }
        rest_dir_[i] = rest;
      }
    }
    offset += s.pointCount();
  }
}

void Simulator::reset() {
  int offset = 0;
  for (const Strip& s : hairstyle_.strips) {
    for (int p = 0; p < s.pointCount(); ++p)
      positions_[static_cast<std::size_t>(offset + p)] = s.points[static_cast<std::size_t>(p)];
    offset += s.pointCount();
  }
  for (std::size_t i = 0; i < positions_.size(); ++i) {
    direction_[i] = styled_dir_[i];
    rate_[i].setZero();
    velocity_[i].setZero();
  }
  offset = 0;
  for (const Strip& s : hairstyle_.strips) {
    for (int r = 1; r < s.rows; ++r)
      for (int c = 0; c < s.columns; ++c) {
        const std::size_t i = static_cast<std::size_t>(offset + s.index(r, c));
        previous_mid_[i] =
            0.5 * (positions_[i] + positions_[static_cast<std::size_t>(offset + s.index(r - 1, c))]);
      }
    offset += s.pointCount();
  }
  steps_ = 0;
  max_rate_ = 0.0;
}

void Simulator::setShape(const std::vector<Vec3>& target) {
  if (target.size() != positions_.size())
    throw std::invalid_argument("Simulator::setShape(...) : " + std::to_string(target.size()) +
                                " points given, the hairstyle has " + std::to_string(positions_.size()));
  for (std::size_t i = 0; i < target.size(); ++i)
    if (!target[i].allFinite())
      throw std::invalid_argument("Simulator::setShape(...) : point " + std::to_string(i) + " is not finite");
  int offset = 0;
  for (const Strip& s : hairstyle_.strips) {
    for (int c = 0; c < s.columns; ++c) {
      std::size_t parent = static_cast<std::size_t>(offset + s.index(0, c));
      for (int r = 1; r < s.rows; ++r) {
        const std::size_t i = static_cast<std::size_t>(offset + s.index(r, c));
        const Vec3 seg = target[i] - target[parent];
        if (seg.norm() > 1e-12) direction_[i] = seg.normalized();
        positions_[i] = positions_[parent] + length_[i] * direction_[i];
        rate_[i].setZero();
        velocity_[i].setZero();
        previous_mid_[i] = positions_[parent] + 0.5 * length_[i] * direction_[i];
        parent = i;
      }
    }
    offset += s.pointCount();
  }
}

void Simulator::step(const StepInputs& in) {
  const double dt = params_.substep;
  const double rho = params_.linear_density;
  const double k = params_.hinge_stiffness;
  const double gamma = params_.hinge_damping;
  const double drag = params_.air_drag;
  const Mat3 Rt = in.head.pose.linear().transpose();
  // World quantities seen from the head frame.
  const Vec3 g = Rt * params_.gravity;
  const Vec3 acc0 = Rt * in.head.linear_acceleration;
  const Vec3 omega = Rt * in.head.angular_velocity;
  const Vec3 alpha = Rt * in.head.angular_acceleration;
  const Vec3 air0 = Rt * (in.wind - in.head.linear_velocity);  // air velocity at the head origin, head frame
  double max_rate = 0.0;

  int offset = 0;
  for (const Strip& s : hairstyle_.strips) {
    for (int c = 0; c < s.columns; ++c) {
      Mat3 Q = Mat3::Identity();  // rotation of the parent segment from its styled frame
      std::size_t parent = static_cast<std::size_t>(offset + s.index(0, c));
      for (int r = 1; r < s.rows; ++r) {
        const std::size_t i = static_cast<std::size_t>(offset + s.index(r, c));
        const double d = length_[i];
        const double inv_i = inv_inertia_[i];
        const Vec3& pivot = positions_[parent];
        const Vec3 n = direction_[i];
        const Vec3 mid = pivot + 0.5 * d * n;
        const Vec3& v = velocity_[i];  // midpoint velocity relative to the head over the last substep
        // (6): F = rho d (g + a) + d f with the fictitious acceleration a of the head frame
        // (linear, angular, centrifugal, Coriolis) and the drag of the air relative to the hair.
        const Vec3 a = -acc0 - alpha.cross(mid) - omega.cross(omega.cross(mid)) - 2.0 * omega.cross(v);
        const Vec3 air = air0 - omega.cross(mid);
        const Vec3 F = rho * d * (g + a) + d * drag * (air - v);
        // (4)-(5): moment of F at the lever d/2 about the two axes perpendicular to the segment.
        Vec3 M = 0.5 * d * n.cross(F);
        // (3): hinge spring toward the rest direction carried by the parent.
        const Vec3 rest = (r == 1) ? rest_dir_[i] : Vec3(Q * rest_dir_[i]);
        M -= k * rotationVectorBetween(rest, n);
        M -= M.dot(n) * n;
        // (7) corrected: I (w^{n+1} - w^n) + gamma dt w^n = dt^2 M.
        Vec3 w = rate_[i] * (1.0 - gamma * dt * inv_i) + (dt * dt * inv_i) * M;
        const double step_angle = w.norm();
        if (step_angle > params_.max_angle_step) w *= params_.max_angle_step / step_angle;
        Vec3 next = rotateByVector(w, n).normalized();
        // Bend limit relative to the rest direction keeps the hinge away from a fold-back.
        const Vec3 bend = rotationVectorBetween(rest, next);
        const double bend_angle = bend.norm();
        if (bend_angle > params_.max_bend)
          next = rotateByVector(bend * (params_.max_bend / bend_angle), rest);
        w = rotationVectorBetween(n, next);
        max_rate = std::max(max_rate, w.norm() / dt);
        rate_[i] = w;
        direction_[i] = next;
        positions_[i] = pivot + d * next;
        const Vec3 mid_next = pivot + 0.5 * d * next;
        velocity_[i] = (mid_next - previous_mid_[i]) / dt;
        previous_mid_[i] = mid_next;
        Q = minimalRotation(Q * styled_dir_[i], next) * Q;
        parent = i;
      }
    }
    offset += s.pointCount();
  }
  max_rate_ = max_rate;
  ++steps_;
}

void Simulator::positionsWorld(const Iso3& head_pose, std::vector<Vec3>& out) const {
  out.resize(positions_.size());
  for (std::size_t i = 0; i < positions_.size(); ++i) out[i] = head_pose * positions_[i];
}

}  // namespace hair_sim
