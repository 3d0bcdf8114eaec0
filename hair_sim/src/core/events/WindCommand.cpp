#include "hair_sim/core/events/WindCommand.hpp"

#include <algorithm>
#include <cmath>

namespace hair_sim {

void WindCommand::set(double start, const Vec3& velocity, double turbulence, double ramp) {
  // From the means at `start`: a fluctuation sampled there and frozen into the next blend would be
  // fluctuated again by it (each command multiplied the wind by up to 1 + 2.2 turbulence, so commands
  // repeated within their ramp made it grow without bound).
  from_ = mean(start);
  turbulence_from_ = this->turbulence(start);
  to_ = velocity;
  turbulence_to_ = turbulence;
  start_ = start;
  ramp_ = ramp;
}

void WindCommand::settle() {
  from_ = to_;
  turbulence_from_ = turbulence_to_;
  start_ = 0.0;
}

double WindCommand::weight(double t) const {
  if (t < start_) return 0.0;
  return ramp_ > 0.0 ? std::min(1.0, (t - start_) / ramp_) : 1.0;
}

Vec3 WindCommand::mean(double t) const {
  const double s = weight(t);
  return (1.0 - s) * from_ + s * to_;
}

double WindCommand::turbulence(double t) const {
  const double s = weight(t);
  return (1.0 - s) * turbulence_from_ + s * turbulence_to_;
}

Vec3 WindCommand::at(double t) const {
  Vec3 w = mean(t);
  const double turbulence = this->turbulence(t);
  if (turbulence > 0.0) {
    // Smooth, deterministic fluctuation: incommensurate sines per axis, relative to the mean speed.
    const double speed = w.norm();
    const Vec3 noise(std::sin(2.1 * t) + 0.5 * std::sin(5.3 * t + 1.0),
                     std::sin(1.7 * t + 2.0) + 0.5 * std::sin(4.1 * t), 0.5 * std::sin(2.9 * t + 0.5));
    w += turbulence * speed * noise / 1.5;
  }
  return w;
}

}  // namespace hair_sim
