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

  // Reaction constraint (8)-(10) against the body ellipsoids.
  double collision_stiffness = 5.0;  ///< k: pushes a control point out of a body (N/m)
  double collision_damping = 0.05;   ///< c: damps its speed into the body (N s/m)

  // Springs (11) within and between strips, with a dead band between the two factors.
  bool springs_within_strips = true;     ///< between neighbouring columns of a strip, same row
  bool springs_between_strips = true;    ///< between control points of neighbouring strips found at rest
  double spring_stiffness = 0.5;         ///< k_s (N/m)
  double spring_proximity_factor = 0.6;  ///< repulsion when closer than this x rest length
  double spring_far_factor = 1.5;        ///< attraction when further than this x rest length
  /// The band's hard near edge as a fraction of spring_proximity_factor: the constraint never places a
  /// pair's points closer than spring_contact_fraction x spring_proximity_factor x rest length. Below 1 the
  /// springs' repulsion acts first and the constraint is a backstop (1: both at the repulsion's edge).
  double spring_contact_fraction = 0.8;
  double spring_radius = 0.02;  ///< pairs between strips: rest distance below this (m)
  int spring_max_pairs = 3;     ///< nearest partners per control point in other strips

  /// Throws std::invalid_argument "PhysicsParameters: <key>: <value> <problem>" on a bad value.
  void validate() const;
};

}  // namespace hair_sim
