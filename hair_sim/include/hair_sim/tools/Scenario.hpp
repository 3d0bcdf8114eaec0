#pragma once
/// Offline scenario: duration, output rate, head keyframes (world frame), wind keyframes and events
/// (the procedural primitives of core/events/Event.hpp: winds add to the keyframed wind, head
/// motions turn the keyframed head about its origin, gravity events change gravity).
/// The head moves along a C1 cubic Hermite curve through the keyframes (Catmull-Rom tangents,
/// zero tangents at the first and last key) in position and in roll/pitch/yaw; the wind is linear
/// between its keys. Before the first and after the last key the values hold. Head keyframes: times at
/// least 1e-6 s apart, positions within +-1e4 m, angles within +-1e3 rad.
#include <string>
#include <vector>

#include "hair_sim/core/TypeDefs.hpp"
#include "hair_sim/core/events/EventSchedule.hpp"

namespace hair_sim {

struct HeadKey {
  double t = 0.0;
  Vec3 position = Vec3::Zero();
  Vec3 rpy = Vec3::Zero();
};

struct WindKey {
  double t = 0.0;
  Vec3 velocity = Vec3::Zero();
};

class Scenario {
 public:
  double duration = 5.0;      ///< s
  double output_rate = 30.0;  ///< Hz
  std::vector<HeadKey> head;  ///< sorted by t, at least one
  std::vector<WindKey> wind;  ///< sorted by t, may be empty (still air)
  std::vector<Event> events;  ///< in file order

  /// Throws std::invalid_argument naming the file, key and value.
  static Scenario load(const std::string& path);
  /// Checks ordering and values; `source` prefixes messages.
  void validate(const std::string& source) const;

  /// The keyframed head pose (without events).
  Iso3 headPose(double t) const;
  /// The keyframed wind (without events).
  Vec3 windVelocity(double t) const;
  /// The events, scheduled.
  EventSchedule schedule() const;
};

}  // namespace hair_sim
