#include "hair_sim/core/model/Hairstyle.hpp"

#include <cmath>
#include <stdexcept>

#include "hair_sim/core/util/YamlReader.hpp"

namespace hair_sim {

int Hairstyle::controlPointCount() const {
  int n = 0;
  for (const Strip& s : strips) n += s.pointCount();
  return n;
}

namespace {
std::string vecString(const Vec3& v) {
  return "[" + formatDouble(v.x()) + ", " + formatDouble(v.y()) + ", " + formatDouble(v.z()) + "]";
}
}  // namespace

void Hairstyle::validate(const std::string& source, double root_tolerance) const {
  if (strips.empty()) throw std::invalid_argument(source + ": strips: the hairstyle has no strips");
  for (std::size_t i = 0; i < strips.size(); ++i) {
    const Strip& s = strips[i];
    const std::string key = source + ": strips[" + std::to_string(i) + "]";
    if (s.columns < Strip::kMinColumns)
      throw std::invalid_argument(key + ".columns: " + std::to_string(s.columns) + " is below the minimum 2");
    if (s.rows < Strip::kMinRows)
      throw std::invalid_argument(key + ".rows: " + std::to_string(s.rows) + " is below the minimum 4");
    if (static_cast<int>(s.points.size()) != s.pointCount()) {
      throw std::invalid_argument(key + ".points: " + std::to_string(s.points.size()) +
                                  " points given, columns x rows = " + std::to_string(s.pointCount()));
    }
    if (!(std::isfinite(s.hair_length) && s.hair_length > 0.0))
      throw std::invalid_argument(key + ".hair_length: " + formatDouble(s.hair_length) + " must be > 0");
    if (!(std::isfinite(s.width) && s.width > 0.0))
      throw std::invalid_argument(key + ".width: " + formatDouble(s.width) + " must be > 0");
    if (!(std::isfinite(s.thickness_margin) && s.thickness_margin >= 0.0))
      throw std::invalid_argument(key + ".thickness_margin: " + formatDouble(s.thickness_margin) +
                                  " must be >= 0");
    for (std::size_t p = 0; p < s.points.size(); ++p) {
      if (!s.points[p].allFinite())
        throw std::invalid_argument(key + ".points[" + std::to_string(p) + "]: " + vecString(s.points[p]) +
                                    " is not finite");
    }
    for (int c = 0; c < s.columns; ++c) {
      for (int r = 1; r < s.rows; ++r) {
        const double d = (s.point(r, c) - s.point(r - 1, c)).norm();
        if (d < 1e-4) {
          throw std::invalid_argument(key + ".points[" + std::to_string(s.index(r, c)) +
                                      "]: segment length " + formatDouble(d) +
                                      " m to the point above is below 1e-4 m");
        }
      }
      const Vec3& root = s.point(0, c);
      const double off = (root - scalp.radialProjection(root)).norm();
      if (off > root_tolerance) {
        throw std::invalid_argument(key + ".points[" + std::to_string(c) + "]: root " + vecString(root) +
                                    " is " + formatDouble(off) + " m off the scalp (tolerance " +
                                    formatDouble(root_tolerance) + " m)");
      }
    }
  }
}

}  // namespace hair_sim
