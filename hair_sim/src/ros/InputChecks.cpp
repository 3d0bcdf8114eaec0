#include "hair_sim/ros/InputChecks.hpp"

#include <cmath>
#include <sstream>

namespace hair_sim {

namespace {

std::string show(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

/// "" if v is finite, else "<name> is <v>".
std::string finite(const std::string& name, double v) {
  return std::isfinite(v) ? std::string() : name + " is " + show(v);
}

}  // namespace

std::string checkWind(const hair_sim_msgs::Wind& msg) {
  const std::pair<const char*, double> fields[] = {{"velocity.x", msg.velocity.x},
                                                   {"velocity.y", msg.velocity.y},
                                                   {"velocity.z", msg.velocity.z},
                                                   {"turbulence", msg.turbulence},
                                                   {"ramp_time", msg.ramp_time}};
  for (const auto& f : fields) {
    const std::string problem = finite(f.first, f.second);
    if (!problem.empty()) return problem;
  }
  if (msg.turbulence < 0.0) return "turbulence is " + show(msg.turbulence) + ", must be >= 0";
  if (msg.turbulence > kMaxTurbulence)
    return "turbulence is " + show(msg.turbulence) + ", must be <= " + show(kMaxTurbulence);
  if (msg.ramp_time < 0.0) return "ramp_time is " + show(msg.ramp_time) + " s, must be >= 0";
  const double speed = std::sqrt(msg.velocity.x * msg.velocity.x + msg.velocity.y * msg.velocity.y +
                                 msg.velocity.z * msg.velocity.z);
  if (!(speed <= kMaxWindSpeed))
    return "velocity is " + show(speed) + " m/s, above " + show(kMaxWindSpeed) + " m/s";
  return "";
}

std::string checkTransform(const geometry_msgs::TransformStamped& t, geometry_msgs::TransformStamped* fixed,
                           bool* normalised) {
  *normalised = false;
  const geometry_msgs::Vector3& p = t.transform.translation;
  const geometry_msgs::Quaternion& q = t.transform.rotation;
  const std::pair<const char*, double> fields[] = {
      {"translation.x", p.x}, {"translation.y", p.y}, {"translation.z", p.z}, {"rotation.x", q.x},
      {"rotation.y", q.y},    {"rotation.z", q.z},    {"rotation.w", q.w}};
  for (const auto& f : fields) {
    const std::string problem = finite(f.first, f.second);
    if (!problem.empty()) return problem;
  }
  const double norm = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
  if (!(norm > 1e-6))
    return "rotation is a zero quaternion (" + show(q.x) + ", " + show(q.y) + ", " + show(q.z) + ", " +
           show(q.w) + ")";
  *fixed = t;
  if (std::abs(norm - 1.0) > 1e-6) {
    fixed->transform.rotation.x = q.x / norm;
    fixed->transform.rotation.y = q.y / norm;
    fixed->transform.rotation.z = q.z / norm;
    fixed->transform.rotation.w = q.w / norm;
    *normalised = true;
  }
  return "";
}

}  // namespace hair_sim
