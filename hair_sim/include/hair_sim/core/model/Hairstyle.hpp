#pragma once
/// A hairstyle: strips plus the scalp ellipsoid their roots sit on, all in the head frame.
#include <string>
#include <vector>

#include "hair_sim/core/collision/Ellipsoid.hpp"
#include "hair_sim/core/model/Strip.hpp"

namespace hair_sim {

struct Hairstyle {
  /// Sanity bounds (head frame, m): hair is at most 10 m long on a head, so far larger numbers are typos,
  /// and beyond 2^21 spring radii the simulator's spring grid overflows (found by fuzz_yaml).
  static constexpr double kMaxCoordinate = 100.0;
  static constexpr double kMaxScalpRadius = 10.0;

  /// Roots must lie on this ellipsoid (head frame).
  Ellipsoid scalp;
  std::vector<Strip> strips;

  /// One strip's first problem (checkStrip): the strip's key ("hair_length", "points", ...), the item of a
  /// sequence key (a point, a colour channel) or -1, and what is wrong. An empty key: no problem.
  struct StripProblem {
    std::string key;
    int item = -1;
    std::string message;
  };

  int controlPointCount() const;
  /// The checks of validate that concern one strip alone, against this hairstyle's scalp (the loader calls it
  /// as it reads each strip, to name the problem's line).
  StripProblem checkStrip(const Strip& strip, double root_tolerance = 2e-3) const;
  /// Checks what every user of a hairstyle relies on, however it was made (the loader, hair_sim_generate,
  /// code): the scalp's radii in (0, kMaxScalpRadius] and its center within +-kMaxCoordinate; each strip's
  /// grid within Strip's limits, its hair_length, width and thickness_margin within Strip's ranges, its
  /// colour channels in [0, 1], its points finite and within +-kMaxCoordinate, consecutive points of a column
  /// at least 1e-4 m apart, its roots on the scalp within root_tolerance (m), and no strip given twice.
  /// Throws std::invalid_argument: "<source>: strips[i].<key>: <problem>" (or "<source>: scalp.<key>: ...").
  void validate(const std::string& source, double root_tolerance = 2e-3) const;
};

}  // namespace hair_sim
