#pragma once
/// Checks of what comes in from the network before it reaches the core (hair_sim_node and its nodelet):
/// each returns "" when the input can be used, else what is wrong with it, naming the field and value.
#include <geometry_msgs/TransformStamped.h>
#include <hair_sim_msgs/Wind.h>

#include <string>

namespace hair_sim {

/// Largest wind speed taken (m/s); faster winds are refused.
constexpr double kMaxWindSpeed = 1000.0;
/// Largest Wind turbulence taken (the fluctuation's standard deviation over the mean speed).
constexpr double kMaxTurbulence = 10.0;

/// A Wind command: finite velocity, turbulence and ramp_time; turbulence in [0, kMaxTurbulence], ramp_time
/// >= 0; speed at most kMaxWindSpeed. (Its frame is checked against tf by the node.)
std::string checkWind(const hair_sim_msgs::Wind& msg);

/// A transform for the tf buffer: a finite translation and rotation and a rotation quaternion that is
/// not (nearly) zero. A quaternion whose norm is off 1 by more than 1e-6 is normalised in `fixed` (a
/// copy of t) and *normalised set, so that tf2 takes it.
std::string checkTransform(const geometry_msgs::TransformStamped& t, geometry_msgs::TransformStamped* fixed,
                           bool* normalised);

}  // namespace hair_sim
