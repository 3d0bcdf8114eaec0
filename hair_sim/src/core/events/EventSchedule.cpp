#include "hair_sim/core/events/EventSchedule.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hair_sim {

namespace {

constexpr double kPi = 3.14159265358979323846;

/// 0 for u <= 0, 1 for u >= 1, 0.5 - 0.5 cos(pi u) between (C1).
double smoothStep(double u) {
  if (u <= 0.0) return 0.0;
  if (u >= 1.0) return 1.0;
  return 0.5 - 0.5 * std::cos(kPi * u);
}

/// A ramp that takes `ease` seconds; a step when ease is 0.
double ramp(double since, double ease) {
  if (ease <= 0.0) return since >= 0.0 ? 1.0 : 0.0;
  return smoothStep(since / ease);
}

std::uint64_t splitMix64(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9E3779B97F4A7C15ULL);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

/// Uniform in [0, 1), the same on every platform for a given state.
double unitRandom(std::uint64_t& state) {
  return static_cast<double>(splitMix64(state) >> 11) * (1.0 / 9007199254740992.0);
}

}  // namespace

Vec3 WindField::at(const Vec3& p) const {
  Vec3 v = Vec3::Zero();
  for (const Wave& w : modes_) v += w.amplitude * std::cos(w.k.dot(p) + w.phase);
  return v;
}

void EventSchedule::add(const Event& event, const std::string& source) {
  event.validate(source);
  Entry entry;
  entry.event = event;
  if (event.type == EventType::Turbulence) {
    // Random plane waves: direction uniform on the sphere, wavelength and period within a factor 3
    // of the scales, amplitude perpendicular to k with |a|^2 = 6 / N, so that sum |a|^2 / 2 = 3: the
    // RMS of each component is 1 on average (times the intensity).
    std::uint64_t state = event.seed * 0xD1B54A32D192ED03ULL + 0x2545F4914F6CDD1DULL;
    const double magnitude = std::sqrt(6.0 / kTurbulenceWaves);
    for (int i = 0; i < kTurbulenceWaves; ++i) {
      const double z = 2.0 * unitRandom(state) - 1.0;
      const double azimuth = 2.0 * kPi * unitRandom(state);
      const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
      const Vec3 dir(r * std::cos(azimuth), r * std::sin(azimuth), z);
      WindField::Wave w;
      w.k = dir * (2.0 * kPi / event.length_scale) * (0.5 + unitRandom(state));
      entry.omega.push_back((2.0 * kPi / event.time_scale) * (0.5 + unitRandom(state)));
      w.phase = 2.0 * kPi * unitRandom(state);
      const double psi = 2.0 * kPi * unitRandom(state);
      const Vec3 e1 = dir.unitOrthogonal(), e2 = dir.cross(e1);
      w.amplitude = magnitude * (std::cos(psi) * e1 + std::sin(psi) * e2);
      entry.waves.push_back(w);
    }
  }
  const auto after = std::upper_bound(entries_.begin(), entries_.end(), event.start,
                                      [](double t, const Entry& e) { return t < e.event.start; });
  entries_.insert(after, std::move(entry));
}

double EventSchedule::end(std::size_t i) const {
  const Event& e = entries_[i].event;
  if (e.duration > 0.0) return e.start + e.duration;
  for (std::size_t j = i + 1; j < entries_.size(); ++j)
    if (entries_[j].event.type == e.type) return entries_[j].event.start + entries_[j].event.ease;
  return std::numeric_limits<double>::infinity();
}

double EventSchedule::endIfAdded(const Event& event) const {
  if (event.duration > 0.0) return event.start + event.duration;
  // add() puts it after the events that start at or before it.
  for (const Entry& entry : entries_)
    if (entry.event.start > event.start && entry.event.type == event.type)
      return entry.event.start + entry.event.ease;
  return std::numeric_limits<double>::infinity();
}

std::size_t EventSchedule::countOverlapping(const Event& event) const {
  const double from = event.start, to = endIfAdded(event);
  std::size_t n = 0;
  for (std::size_t i = 0; i < entries_.size(); ++i) {
    const Event& e = entries_[i].event;
    if (e.type != event.type) continue;
    // An event until replaced that starts before `event` ends at event's ease once it is added.
    double ends = end(i);
    if (e.duration <= 0.0 && e.start <= event.start) ends = std::min(ends, event.start + event.ease);
    if (e.start < to && ends > from) ++n;
  }
  return n;
}

void EventSchedule::dropEndedBefore(double t) {
  std::vector<Entry> kept;
  for (std::size_t i = 0; i < entries_.size(); ++i)
    if (end(i) >= t) kept.push_back(entries_[i]);
  entries_.swap(kept);
}

double EventSchedule::envelope(std::size_t i, double t) const {
  const Event& e = entries_[i].event;
  if (t < e.start) return 0.0;
  const double in = ramp(t - e.start, e.ease);
  if (e.duration > 0.0) {
    if (t >= e.start + e.duration) return 0.0;
    return in * (e.ease > 0.0 ? smoothStep((e.start + e.duration - t) / e.ease) : 1.0);
  }
  // Until replaced: the next event of the same type takes over during its own ease.
  for (std::size_t j = i + 1; j < entries_.size(); ++j) {
    const Event& next = entries_[j].event;
    if (next.type != e.type) continue;
    return in * (1.0 - ramp(t - next.start, next.ease));
  }
  return in;
}

double EventSchedule::gustCrest(const Event& e, long k) {
  std::uint64_t state =
      (e.seed * 0x9E3779B97F4A7C15ULL) ^ (static_cast<std::uint64_t>(k) * 0xC2B2AE3D27D4EB4FULL);
  return e.start + (static_cast<double>(k) + 0.5 + e.jitter * (unitRandom(state) - 0.5)) * e.period;
}

double EventSchedule::gustSpeed(const Event& e, double t) {
  // Raised-cosine gusts of half-width period / 4 on a base speed: the crest reaches `peak`, and since
  // a gust averages 1/4 over its period, base = (4 mean - peak) / 3 makes the time average `mean`.
  const double mean = e.vector.norm();
  const double base = (4.0 * mean - e.peak) / 3.0;
  const double half_width = 0.25 * e.period;
  const long k0 = static_cast<long>(std::floor((t - e.start) / e.period));
  double pulses = 0.0;
  for (long k = std::max(0L, k0 - 1); k <= k0 + 1; ++k) {
    const double tau = t - gustCrest(e, k);
    if (std::abs(tau) < half_width) pulses += 0.5 * (1.0 + std::cos(kPi * tau / half_width));
  }
  return base + (e.peak - base) * pulses;
}

EventSample EventSchedule::sample(double t, const Vec3& gravity) const {
  EventSample out;
  out.gravity = gravity;
  for (std::size_t i = 0; i < entries_.size(); ++i) {
    const Event& e = entries_[i].event;
    if (t < e.start) break;  // sorted by start
    const double w = envelope(i, t);
    if (w <= 0.0) continue;
    ++out.active;
    const double tau = t - e.start;
    switch (e.type) {
      case EventType::Wind:
        out.wind += w * e.vector;
        break;
      case EventType::WindGust:
        out.wind += w * gustSpeed(e, t) * e.vector.normalized();
        break;
      case EventType::Turbulence:
        for (std::size_t m = 0; m < entries_[i].waves.size(); ++m) {
          WindField::Wave wave = entries_[i].waves[m];
          wave.phase -= entries_[i].omega[m] * tau;
          wave.amplitude *= w * e.intensity;
          out.turbulence.modes_.push_back(wave);
        }
        break;
      case EventType::Gravity:
        // Blended in order of start, so a later event wins over an earlier one where both are in full.
        // An event being replaced stays in full during the hand-over: the newcomer's own ease blends
        // from it (fading it out as well would dip toward the configured gravity half way).
        out.gravity += (e.duration > 0.0 ? w : ramp(tau, e.ease)) * (e.vector - out.gravity);
        break;
      case EventType::Nod:
        out.head_rotation *=
            Eigen::AngleAxisd(w * e.amplitude * std::sin(2.0 * kPi * e.frequency * tau), Vec3::UnitY())
                .toRotationMatrix();
        break;
      case EventType::Shake:
        out.head_rotation *=
            Eigen::AngleAxisd(w * e.amplitude * std::sin(2.0 * kPi * e.frequency * tau), Vec3::UnitZ())
                .toRotationMatrix();
        break;
      case EventType::Tilt:
        out.head_rotation *=
            Eigen::AngleAxisd(w * e.amplitude * std::sin(2.0 * kPi * e.frequency * tau), Vec3::UnitX())
                .toRotationMatrix();
        break;
      case EventType::Turn:
        out.head_rotation *= Eigen::AngleAxisd(w * e.amplitude, Vec3::UnitZ()).toRotationMatrix();
        break;
    }
  }
  return out;
}

}  // namespace hair_sim
