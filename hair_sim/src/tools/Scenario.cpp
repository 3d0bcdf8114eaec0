#include "hair_sim/tools/Scenario.hpp"

#include <stdexcept>

#include "hair_sim/core/util/YamlReader.hpp"

namespace hair_sim {

namespace {
constexpr double kMaxHeadCoordinate = 1e4;  ///< m
constexpr double kMaxHeadAngle = 1e3;       ///< rad
constexpr double kMinKeySpacing = 1e-6;     ///< s between head keyframes
}  // namespace

Scenario Scenario::load(const std::string& path) {
  const YamlReader y = YamlReader::loadFile(path);
  y.requireKeys({"duration", "output_rate", "head", "wind", "events"});
  Scenario s;
  s.duration = y.getDouble("duration", 1e-3, 86400.0);
  s.output_rate = y.getDouble("output_rate", 0.1, 10000.0, s.output_rate);
  const YamlReader head = y.child("head");
  head.requireSequence(1);
  for (std::size_t i = 0; i < head.size(); ++i) {
    const YamlReader k = head.at(i);
    k.requireKeys({"t", "position", "rpy"});
    HeadKey key;
    key.t = k.getDouble("t", 0.0, 1e6);
    key.position = k.getVec3("position", Vec3::Zero());
    key.rpy = k.getVec3("rpy", Vec3::Zero());
    // Bounds that keep the cubic's tangents (differences over time differences) finite (fuzz_yaml found
    // positions of 1e308 turning the head pose into NaN).
    if (!(key.position.cwiseAbs().maxCoeff() <= kMaxHeadCoordinate))
      throw k.error("position",
                    "every coordinate must be within +-" + formatDouble(kMaxHeadCoordinate) + " m");
    if (!(key.rpy.cwiseAbs().maxCoeff() <= kMaxHeadAngle))
      throw k.error("rpy", "every angle must be within +-" + formatDouble(kMaxHeadAngle) + " rad");
    if (!s.head.empty() && !(key.t >= s.head.back().t + kMinKeySpacing))
      throw k.error("t", formatDouble(key.t) + " s is not at least " + formatDouble(kMinKeySpacing) +
                             " s after the previous keyframe's " + formatDouble(s.head.back().t) + " s");
    s.head.push_back(key);
  }
  if (y.has("wind")) {
    const YamlReader wind = y.child("wind");
    wind.requireSequence();
    for (std::size_t i = 0; i < wind.size(); ++i) {
      const YamlReader k = wind.at(i);
      k.requireKeys({"t", "velocity"});
      WindKey key;
      key.t = k.getDouble("t", 0.0, 1e6);
      key.velocity = k.getVec3("velocity");
      if (key.velocity.norm() > 1000.0) throw k.error("velocity", "wind speed above 1000 m/s");
      if (!s.wind.empty() && key.t <= s.wind.back().t)
        throw k.error("t", formatDouble(key.t) + " s is not after the previous keyframe's " +
                               formatDouble(s.wind.back().t) + " s");
      s.wind.push_back(key);
    }
  }
  if (y.has("events")) {
    const YamlReader events = y.child("events");
    events.requireSequence();
    for (std::size_t i = 0; i < events.size(); ++i) s.events.push_back(Event::fromYaml(events.at(i)));
  }
  s.validate(path);
  return s;
}

void Scenario::validate(const std::string& source) const {
  if (head.empty()) throw std::invalid_argument(source + ": head: at least one keyframe is needed");
  for (std::size_t i = 1; i < head.size(); ++i)
    if (!(head[i].t > head[i - 1].t))
      throw std::invalid_argument(source + ": head[" + std::to_string(i) +
                                  "].t: keyframe times must increase");
  for (std::size_t i = 1; i < wind.size(); ++i)
    if (!(wind[i].t > wind[i - 1].t))
      throw std::invalid_argument(source + ": wind[" + std::to_string(i) +
                                  "].t: keyframe times must increase");
  if (!(duration > 0.0))
    throw std::invalid_argument(source + ": duration: " + formatDouble(duration) + " must be > 0");
  if (!(output_rate > 0.0))
    throw std::invalid_argument(source + ": output_rate: " + formatDouble(output_rate) + " must be > 0");
  for (std::size_t i = 0; i < events.size(); ++i)
    events[i].validate(source + ": events[" + std::to_string(i) + "]");
}

EventSchedule Scenario::schedule() const {
  EventSchedule out;
  for (const Event& e : events) out.add(e);
  return out;
}

namespace {

/// Catmull-Rom tangent at key i (zero at the ends), for a value picked by `get`.
template <typename Get>
Vec3 tangent(const std::vector<HeadKey>& keys, std::size_t i, Get get) {
  if (i == 0 || i + 1 >= keys.size()) return Vec3::Zero();
  return (get(keys[i + 1]) - get(keys[i - 1])) / (keys[i + 1].t - keys[i - 1].t);
}

template <typename Get>
Vec3 hermite(const std::vector<HeadKey>& keys, double t, Get get) {
  if (t <= keys.front().t) return get(keys.front());
  if (t >= keys.back().t) return get(keys.back());
  std::size_t i = 0;
  while (keys[i + 1].t < t) ++i;
  const double h = keys[i + 1].t - keys[i].t;
  const double s = (t - keys[i].t) / h;
  const double s2 = s * s, s3 = s2 * s;
  const double h00 = 2 * s3 - 3 * s2 + 1, h10 = s3 - 2 * s2 + s, h01 = -2 * s3 + 3 * s2, h11 = s3 - s2;
  return h00 * get(keys[i]) + h10 * h * tangent(keys, i, get) + h01 * get(keys[i + 1]) +
         h11 * h * tangent(keys, i + 1, get);
}

}  // namespace

Iso3 Scenario::headPose(double t) const {
  const Vec3 p = hermite(head, t, [](const HeadKey& k) { return k.position; });
  const Vec3 rpy = hermite(head, t, [](const HeadKey& k) { return k.rpy; });
  Iso3 pose = Iso3::Identity();
  pose.linear() = rotationFromRpy(rpy);
  pose.translation() = p;
  return pose;
}

Vec3 Scenario::windVelocity(double t) const {
  if (wind.empty()) return Vec3::Zero();
  if (t <= wind.front().t) return wind.front().velocity;
  if (t >= wind.back().t) return wind.back().velocity;
  std::size_t i = 0;
  while (wind[i + 1].t < t) ++i;
  const double s = (t - wind[i].t) / (wind[i + 1].t - wind[i].t);
  return (1.0 - s) * wind[i].velocity + s * wind[i + 1].velocity;
}

}  // namespace hair_sim
