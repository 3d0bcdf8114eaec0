#pragma once
/// A hairstyle: strips plus the scalp ellipsoid their roots sit on, all in the head frame.
#include <string>
#include <vector>

#include "hair_sim/core/collision/Ellipsoid.hpp"
#include "hair_sim/core/model/Strip.hpp"

namespace hair_sim {

struct Hairstyle {
  /// Roots must lie on this ellipsoid (head frame).
  Ellipsoid scalp;
  std::vector<Strip> strips;

  int controlPointCount() const;
  /// Checks sizes, finiteness, distinct consecutive points and that roots lie on the scalp within
  /// root_tolerance (m). Throws std::invalid_argument: "<source>: strips[i].<key>: <problem>".
  void validate(const std::string& source, double root_tolerance = 2e-3) const;
};

}  // namespace hair_sim
