#pragma once
/// Physical constants of the strip dynamics (paper 4.2) and their numerical safeguards.
/// Units SI. Defaults are the ones in config/hair_sim.yaml.
#include <string>

#include "hair_sim/core/TypeDefs.hpp"

namespace hair_sim {

struct PhysicsParameters {
  double substep = 1.0 / 240.0;        ///< fixed internal time step (s)
  Vec3 gravity{0.0, 0.0, -9.81};       ///< world frame (m/s^2)
  double linear_density = 0.01;        ///< rho: mass per metre of one control-point column (kg/m)
  double hinge_stiffness = 4e-4;       ///< k_theta = k_phi: hinge spring to the rest angles (N m/rad)
  double hinge_damping = 1e-5;         ///< gamma: angular damping (N m s/rad)
  double air_drag = 0.02;              ///< f = air_drag * (air velocity relative to the hair) (N s/m^2)
  double max_angle_step = 0.35;        ///< largest rotation of one segment in one substep (rad)
  double max_bend = 2.4;               ///< largest deviation of a segment from its rest direction (rad)
  bool compensate_rest_angles = true;  ///< styled shape = equilibrium under gravity at the rest pose

  /// Throws std::invalid_argument "PhysicsParameters: <key>: <value> <problem>" on a bad value.
  void validate() const;
};

}  // namespace hair_sim
