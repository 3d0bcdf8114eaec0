#include "hair_sim/core/events/Event.hpp"

#include <cmath>
#include <stdexcept>

#include "hair_sim/core/util/YamlReader.hpp"

namespace hair_sim {

namespace {

constexpr double kPi = 3.14159265358979323846;

struct TypeName {
  EventType type;
  const char* name;
};
constexpr TypeName kTypes[] = {{EventType::Wind, "wind"},
                               {EventType::WindGust, "wind_gust"},
                               {EventType::Turbulence, "turbulence"},
                               {EventType::Gravity, "gravity"},
                               {EventType::Nod, "nod"},
                               {EventType::Shake, "shake"},
                               {EventType::Turn, "turn"},
                               {EventType::Tilt, "tilt"}};

}  // namespace

const char* eventTypeName(EventType type) {
  for (const TypeName& t : kTypes)
    if (t.type == type) return t.name;
  return "?";
}

bool parseEventType(const std::string& name, EventType* type) {
  for (const TypeName& t : kTypes)
    if (name == t.name) {
      *type = t.type;
      return true;
    }
  return false;
}

std::string eventTypeNames() {
  std::string out;
  for (const TypeName& t : kTypes) out += (out.empty() ? "" : ", ") + std::string(t.name);
  return out;
}

bool isHeadMotion(EventType type) {
  return type == EventType::Nod || type == EventType::Shake || type == EventType::Turn ||
         type == EventType::Tilt;
}

bool Event::findProblem(std::string* field, std::string* message) const {
  auto fail = [&](const std::string& f, const std::string& value, const std::string& rule) {
    *field = f;
    *message = value + " " + rule;
    return true;
  };
  auto outside = [](double v, double lo, double hi) { return !(std::isfinite(v) && v >= lo && v <= hi); };
  auto range = [](double lo, double hi, const char* unit) {
    return "must be in [" + formatDouble(lo) + ", " + formatDouble(hi) + "] " + unit;
  };
  auto show = [](const Vec3& v) {
    return "[" + formatDouble(v.x()) + ", " + formatDouble(v.y()) + ", " + formatDouble(v.z()) + "]";
  };
  if (outside(start, 0.0, 1e12)) return fail("start", formatDouble(start), range(0.0, 1e12, "s"));
  if (outside(duration, 0.0, 1e9)) return fail("duration", formatDouble(duration), range(0.0, 1e9, "s"));
  if (outside(ease, 0.0, 1e6)) return fail("ease", formatDouble(ease), range(0.0, 1e6, "s"));
  if (duration > 0.0 && ease > 0.5 * duration)
    return fail("ease", formatDouble(ease),
                "must be at most half the duration " + formatDouble(duration) + " s");
  switch (type) {
    case EventType::Wind:
      if (!vector.allFinite() || vector.norm() > 1000.0)
        return fail("velocity", show(vector), "must be finite and at most 1000 m/s");
      break;
    case EventType::WindGust: {
      const double mean = vector.norm();
      if (!vector.allFinite() || !(mean > 0.0) || mean > 1000.0)
        return fail("mean", show(vector),
                    "must be a non-zero velocity (the gusts' direction) up to 1000 m/s");
      if (outside(peak, mean, 4.0 * mean))
        return fail("peak", formatDouble(peak),
                    "must be between the mean speed " + formatDouble(mean) + " and 4 times it (m/s)");
      if (outside(period, 1e-3, 1e6)) return fail("period", formatDouble(period), range(1e-3, 1e6, "s"));
      if (outside(jitter, 0.0, 0.5))
        return fail("jitter", formatDouble(jitter), range(0.0, 0.5, "(periods)"));
      break;
    }
    case EventType::Turbulence:
      if (outside(intensity, 0.0, 100.0))
        return fail("intensity", formatDouble(intensity), range(0, 100, "m/s"));
      if (outside(length_scale, 1e-3, 1e3))
        return fail("length_scale", formatDouble(length_scale), range(1e-3, 1e3, "m"));
      if (outside(time_scale, 1e-3, 1e3))
        return fail("time_scale", formatDouble(time_scale), range(1e-3, 1e3, "s"));
      break;
    case EventType::Gravity:
      if (!vector.allFinite() || vector.norm() > 100.0)
        return fail("acceleration", show(vector), "must be finite and at most 100 m/s^2");
      break;
    case EventType::Nod:
    case EventType::Shake:
    case EventType::Tilt:
      if (outside(amplitude, -kPi / 2.0, kPi / 2.0))
        return fail("amplitude", formatDouble(amplitude), range(-kPi / 2.0, kPi / 2.0, "rad"));
      if (outside(frequency, 1e-3, 20.0))
        return fail("frequency", formatDouble(frequency), range(1e-3, 20, "Hz"));
      break;
    case EventType::Turn:
      if (outside(amplitude, -kPi, kPi))
        return fail("amplitude", formatDouble(amplitude), range(-kPi, kPi, "rad"));
      break;
  }
  return false;
}

void Event::validate(const std::string& source) const {
  std::string field, message;
  if (findProblem(&field, &message))
    throw std::invalid_argument(source + ": " + eventTypeName(type) + " event: " + field + ": " + message);
}

Event Event::fromYaml(const YamlReader& y) {
  Event e;
  const std::string type = y.getString("type");
  if (!parseEventType(type, &e.type))
    throw y.error("type", "'" + type + "' is not one of " + eventTypeNames());
  switch (e.type) {
    case EventType::Wind:
      y.requireKeys({"type", "start", "duration", "ease", "velocity"});
      e.vector = y.getVec3("velocity");
      break;
    case EventType::WindGust:
      y.requireKeys({"type", "start", "duration", "ease", "mean", "peak", "period", "jitter", "seed"});
      e.vector = y.getVec3("mean");
      e.peak = y.getDouble("peak", 0.0, 1000.0);
      e.period = y.getDouble("period", 1e-3, 1e6);
      e.jitter = y.getDouble("jitter", 0.0, 0.5, e.jitter);
      e.seed = static_cast<std::uint64_t>(y.getInt("seed", 0, 2147483647, 1));
      break;
    case EventType::Turbulence:
      y.requireKeys({"type", "start", "duration", "ease", "intensity", "length_scale", "time_scale", "seed"});
      e.intensity = y.getDouble("intensity", 0.0, 100.0);
      e.length_scale = y.getDouble("length_scale", 1e-3, 1e3, e.length_scale);
      e.time_scale = y.getDouble("time_scale", 1e-3, 1e3, e.time_scale);
      e.seed = static_cast<std::uint64_t>(y.getInt("seed", 0, 2147483647, 1));
      break;
    case EventType::Gravity:
      y.requireKeys({"type", "start", "duration", "ease", "acceleration"});
      e.vector = y.getVec3("acceleration");
      break;
    case EventType::Nod:
    case EventType::Shake:
    case EventType::Tilt:
      y.requireKeys({"type", "start", "duration", "ease", "amplitude", "frequency"});
      e.amplitude = y.getDouble("amplitude", -kPi / 2.0, kPi / 2.0);
      e.frequency = y.getDouble("frequency", 1e-3, 20.0);
      break;
    case EventType::Turn:
      y.requireKeys({"type", "start", "duration", "ease", "amplitude"});
      e.amplitude = y.getDouble("amplitude", -kPi, kPi);
      break;
  }
  e.start = y.getDouble("start", 0.0, 1e12);
  e.duration = y.getDouble("duration", 0.0, 1e9, 0.0);
  e.ease = y.getDouble("ease", 0.0, 1e6, 0.0);
  std::string field, message;
  if (e.findProblem(&field, &message)) throw y.error(field, message + " (" + type + " event)");
  return e;
}

}  // namespace hair_sim
