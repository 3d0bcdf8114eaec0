#pragma once
/// Eigen aliases and small value types shared by the whole core (no ROS here).
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace hair_sim {

using Vec3 = Eigen::Vector3d;
using Vec3f = Eigen::Vector3f;
using Mat3 = Eigen::Matrix3d;
using Quat = Eigen::Quaterniond;
using Iso3 = Eigen::Isometry3d;

/// Linear RGBA colour, each channel in [0, 1].
struct Rgba {
  float r = 0.f;
  float g = 0.f;
  float b = 0.f;
  float a = 1.f;
};

/// Rotation matrix from roll, pitch, yaw (rad), fixed axes X then Y then Z (REP-103: R = Rz(yaw) Ry(pitch)
/// Rx(roll)).
inline Mat3 rotationFromRpy(const Vec3& rpy) {
  return (Eigen::AngleAxisd(rpy.z(), Vec3::UnitZ()) * Eigen::AngleAxisd(rpy.y(), Vec3::UnitY()) *
          Eigen::AngleAxisd(rpy.x(), Vec3::UnitX()))
      .toRotationMatrix();
}

}  // namespace hair_sim
