#pragma once
/// The events in force at a time: what they add up to (wind, gravity, head rotation), sampled by
/// simulated time only, deterministic for given seeds. See Event.hpp for the primitives.
#include <cstddef>
#include <vector>

#include "hair_sim/core/events/Event.hpp"

namespace hair_sim {

/// Turbulence at one instant: a sum of plane waves a_i cos(k_i . p + phase_i) with a_i perpendicular
/// to k_i (so the field is divergence-free), world frame.
class WindField {
 public:
  bool empty() const { return modes_.empty(); }
  /// Air velocity of the turbulence at a world point (m/s).
  Vec3 at(const Vec3& p) const;
  /// Multiplies the field by `factor` (hair_sim_node's ~wind_scale, as for the uniform wind).
  void scale(double factor) {
    for (Wave& w : modes_) w.amplitude *= factor;
  }

 private:
  friend class EventSchedule;
  struct Wave {
    Vec3 k;
    double phase;
    Vec3 amplitude;
  };
  std::vector<Wave> modes_;
};

/// What the events add up to at one time.
struct EventSample {
  Vec3 wind = Vec3::Zero();               ///< uniform air velocity from wind and gusts (m/s)
  Vec3 gravity = Vec3(0.0, 0.0, -9.81);   ///< m/s^2
  Mat3 head_rotation = Mat3::Identity();  ///< head pose = base pose * this (head frame)
  WindField turbulence;                   ///< add turbulence.at(p) at world point p
  int active = 0;                         ///< events with a non-zero envelope
};

class EventSchedule {
 public:
  /// Number of plane waves of one turbulence event.
  static constexpr int kTurbulenceWaves = 16;

  /// Validates (throws std::invalid_argument naming `source`, the field and the value) and adds;
  /// events stay sorted by start (equal starts keep the order they came in).
  void add(const Event& event, const std::string& source = "event");
  void clear() { entries_.clear(); }
  std::size_t size() const { return entries_.size(); }
  const Event& event(std::size_t i) const { return entries_[i].event; }
  /// Drops events whose effect ended before t (s).
  void dropEndedBefore(double t);

  /// The envelope of event i at t: 0 before its start, eases to 1, back to 0 at its end.
  double envelope(std::size_t i, double t) const;
  /// When event i stops acting (s): start + duration, or for duration 0 the end of the ease of the
  /// next event of its type (infinity if there is none).
  double end(std::size_t i) const;
  /// When `event` would stop acting were it added now (as end() would give after add): start + duration,
  /// or for duration 0 the end of the ease of the first event of its type that starts later (infinity if
  /// there is none).
  double endIfAdded(const Event& event) const;
  /// The events of `event`'s type that act at some time while it would (from its start to endIfAdded), as
  /// they stand: at least the most that would act together with it at any one time.
  std::size_t countOverlapping(const Event& event) const;
  /// Wind, gravity (from `gravity`, the configured one) and head rotation at time t (s).
  EventSample sample(double t, const Vec3& gravity) const;

  /// Wind gust train of one event without its envelope: the speed along the mean direction (m/s).
  static double gustSpeed(const Event& e, double t);
  /// Time of the crest of gust k (k = 0, 1, ...) of a wind_gust event.
  static double gustCrest(const Event& e, long k);

 private:
  struct Entry {
    Event event;
    std::vector<WindField::Wave> waves;  ///< turbulence: k, phase at t = start, unit-intensity amplitude
    std::vector<double> omega;           ///< turbulence: angular frequency of each wave
  };
  std::vector<Entry> entries_;
};

}  // namespace hair_sim
