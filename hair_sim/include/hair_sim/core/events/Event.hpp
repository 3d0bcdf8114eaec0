#pragma once
/// Event-triggered procedural primitives (paper section 4.4): wind, gravity and head movement,
/// each switched on at a time, for a while, with a smooth ease in and out.
///
/// Every event has a `type`, a `start` (s, simulated time), a `duration` (s; 0 = until the next
/// event of the same type starts, which then takes over during its own ease), an `ease` (s, the
/// 0.5 - 0.5 cos ramp in and out) and the parameters of its type:
///   wind        vector = air velocity (m/s, world frame), constant
///   wind_gust   vector = mean air velocity (m/s; its direction is the gusts' direction), peak (m/s,
///               the speed at the crest of each gust), period (s, one gust per period), jitter
///               (0..0.5: each gust's crest moves by up to +-jitter/2 periods, seeded), seed
///   turbulence  intensity (m/s: RMS of each velocity component), length_scale (m), time_scale (s),
///               seed: a smooth, divergence-free random field in space and time
///   gravity     vector = gravitational acceleration (m/s^2, world frame) the configured one blends to
///   nod, shake, tilt   amplitude (rad), frequency (Hz): the head pitches (nose down for positive),
///               yaws or rolls by amplitude sin(2 pi frequency (t - start)) about its own origin
///   turn        amplitude (rad): the head yaws to amplitude and holds (the ease sets how fast)
/// Winds add; head motions compose (in order of start); gravity events blend in order of start.
#include <cstdint>
#include <string>

#include "hair_sim/core/TypeDefs.hpp"

namespace hair_sim {

class YamlReader;

enum class EventType { Wind, WindGust, Turbulence, Gravity, Nod, Shake, Turn, Tilt };

/// "wind", "wind_gust", ... as in files and messages.
const char* eventTypeName(EventType type);
/// Parses a type name; false if it is none of them.
bool parseEventType(const std::string& name, EventType* type);
/// The names of all types, comma-separated (for messages).
std::string eventTypeNames();
/// nod, shake, turn, tilt: the head driver's business, not the hair's.
bool isHeadMotion(EventType type);

struct Event {
  EventType type = EventType::Wind;
  double start = 0.0;          ///< s, simulated time
  double duration = 0.0;       ///< s, 0 = until replaced by the next event of the same type
  double ease = 0.0;           ///< s, ramp in and out
  Vec3 vector = Vec3::Zero();  ///< wind: velocity; wind_gust: mean velocity (m/s); gravity (m/s^2); world
  double peak = 0.0;           ///< wind_gust: speed at a gust's crest (m/s)
  double period = 2.0;         ///< wind_gust: s
  double jitter = 0.0;         ///< wind_gust: in [0, 0.5]
  double intensity = 0.0;      ///< turbulence: m/s
  double length_scale = 0.5;   ///< turbulence: m
  double time_scale = 1.0;     ///< turbulence: s
  double amplitude = 0.0;      ///< nod, shake, tilt, turn: rad
  double frequency = 1.0;      ///< nod, shake, tilt: Hz
  std::uint64_t seed = 1;      ///< wind_gust, turbulence

  /// The first bad value: its field (named as in files: velocity, mean, acceleration, peak, ...) and
  /// "<value> <rule>"; false if every value is good.
  bool findProblem(std::string* field, std::string* message) const;
  /// Throws std::invalid_argument "<source>: <type> event: <field>: <value> <rule>" on a bad value.
  void validate(const std::string& source) const;
  /// Reads one event from a YAML map (type, start, duration, ease and the keys of its type; keys of
  /// other types are errors). Throws std::invalid_argument naming file, key, line and value.
  static Event fromYaml(const YamlReader& y);
};

}  // namespace hair_sim
