#pragma once
/// A collision body: an ellipsoid attached to a named frame (a tf frame in the node; in the offline
/// runner the head frame follows the scenario and the world frame stays fixed).
#include <string>

#include "hair_sim/core/collision/Ellipsoid.hpp"

namespace hair_sim {

struct Body {
  std::string name;
  std::string frame;
  /// Shape in `frame` (centre, orientation, radii).
  Ellipsoid shape;
};

}  // namespace hair_sim
