#include "hair_sim/core/model/PhysicsParameters.hpp"

#include <cmath>
#include <stdexcept>

#include "hair_sim/core/util/YamlReader.hpp"

namespace hair_sim {

namespace {
void check(bool ok, const char* key, double value, const char* rule) {
  if (!ok || !std::isfinite(value))
    throw std::invalid_argument(std::string("PhysicsParameters: ") + key + ": " + formatDouble(value) + " " +
                                rule);
}
}  // namespace

void PhysicsParameters::validate() const {
  check(substep > 0.0 && substep <= 0.05, "substep", substep, "must be in (0, 0.05] s");
  check(gravity.allFinite(), "gravity", gravity.norm(), "must be finite");
  check(linear_density > 0.0, "linear_density", linear_density, "must be > 0 kg/m");
  check(hinge_stiffness >= 0.0, "hinge_stiffness", hinge_stiffness, "must be >= 0 N m/rad");
  check(hinge_damping >= 0.0, "hinge_damping", hinge_damping, "must be >= 0 N m s/rad");
  check(air_drag >= 0.0, "air_drag", air_drag, "must be >= 0 N s/m^2");
  check(max_angle_step > 0.0 && max_angle_step <= 1.5, "max_angle_step", max_angle_step,
        "must be in (0, 1.5] rad");
  check(collision_stiffness >= 0.0, "collision_stiffness", collision_stiffness, "must be >= 0 N/m");
  check(collision_damping >= 0.0, "collision_damping", collision_damping, "must be >= 0 N s/m");
  check(spring_stiffness >= 0.0, "spring_stiffness", spring_stiffness, "must be >= 0 N/m");
  check(spring_proximity_factor > 0.0 && spring_proximity_factor <= 1.0, "spring_proximity_factor",
        spring_proximity_factor, "must be in (0, 1]");
  check(spring_far_factor >= 1.0, "spring_far_factor", spring_far_factor, "must be >= 1");
  check(spring_contact_fraction >= 0.01 && spring_contact_fraction <= 1.0, "spring_contact_fraction",
        spring_contact_fraction, "must be in [0.01, 1]");
  check(spring_radius >= 0.0 && spring_radius <= 0.5, "spring_radius", spring_radius,
        "must be in [0, 0.5] m");
  check(spring_max_pairs >= 0 && spring_max_pairs <= 16, "spring_max_pairs", spring_max_pairs,
        "must be in [0, 16]");
  check(max_bend > 0.0 && max_bend <= 3.0, "max_bend", max_bend, "must be in (0, 3.0] rad");
}

}  // namespace hair_sim
