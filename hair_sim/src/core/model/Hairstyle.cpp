#include "hair_sim/core/model/Hairstyle.hpp"

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <unordered_map>

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

/// "<key>: <value> is outside [lo, hi]" unless lo <= value <= hi (NaN is outside).
void requireWithin(const std::string& key, double value, double lo, double hi) {
  if (!(value >= lo && value <= hi))
    throw std::invalid_argument(key + ": " + formatDouble(value) + " is outside [" + formatDouble(lo) + ", " +
                                formatDouble(hi) + "]");
}

/// "<key>: <vec> is not finite" or "... is beyond +-100 m of the head frame's origin".
void requireCoordinates(const std::string& key, const Vec3& p) {
  if (!p.allFinite()) throw std::invalid_argument(key + ": " + vecString(p) + " is not finite");
  if (!(p.cwiseAbs().maxCoeff() <= Hairstyle::kMaxCoordinate))
    throw std::invalid_argument(key + ": " + vecString(p) + " has a coordinate beyond +-" +
                                formatDouble(Hairstyle::kMaxCoordinate) + " m of the head frame's origin");
}

}  // namespace

void Hairstyle::validate(const std::string& source, double root_tolerance) const {
  requireCoordinates(source + ": scalp.center", scalp.center());
  for (int a = 0; a < 3; ++a) {
    if (!(scalp.radii()[a] > 0.0 && scalp.radii()[a] <= kMaxScalpRadius))
      throw std::invalid_argument(source + ": scalp.radii: every radius must be in (0, " +
                                  formatDouble(kMaxScalpRadius) + "] m, got " + vecString(scalp.radii()));
  }
  if (strips.empty()) throw std::invalid_argument(source + ": strips: the hairstyle has no strips");
  for (std::size_t i = 0; i < strips.size(); ++i) {
    const Strip& s = strips[i];
    const std::string key = source + ": strips[" + std::to_string(i) + "]";
    if (s.columns < Strip::kMinColumns || s.columns > Strip::kMaxColumns)
      throw std::invalid_argument(key + ".columns: " + std::to_string(s.columns) + " is outside [" +
                                  std::to_string(Strip::kMinColumns) + ", " +
                                  std::to_string(Strip::kMaxColumns) + "]");
    if (s.rows < Strip::kMinRows || s.rows > Strip::kMaxRows)
      throw std::invalid_argument(key + ".rows: " + std::to_string(s.rows) + " is outside [" +
                                  std::to_string(Strip::kMinRows) + ", " + std::to_string(Strip::kMaxRows) +
                                  "]");
    if (static_cast<int>(s.points.size()) != s.pointCount()) {
      throw std::invalid_argument(key + ".points: " + std::to_string(s.points.size()) +
                                  " points given, columns x rows = " + std::to_string(s.pointCount()));
    }
    requireWithin(key + ".hair_length", s.hair_length, Strip::kMinHairLength, Strip::kMaxHairLength);
    requireWithin(key + ".width", s.width, Strip::kMinWidth, Strip::kMaxWidth);
    requireWithin(key + ".thickness_margin", s.thickness_margin, 0.0, Strip::kMaxThicknessMargin);
    const float channels[4] = {s.color.r, s.color.g, s.color.b, s.color.a};
    for (int c = 0; c < 4; ++c)
      requireWithin(key + ".color[" + std::to_string(c) + "]", channels[c], 0.0, 1.0);
    for (std::size_t p = 0; p < s.points.size(); ++p)
      requireCoordinates(key + ".points[" + std::to_string(p) + "]", s.points[p]);
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
  // A strip given twice (a copy and paste): its points would all share cells with the other's, and the
  // springs' neighbour search scans a cell's points for each of its points (20,000 copies of one strip took
  // minutes there).
  std::unordered_map<std::uint64_t, std::size_t> first_root;  // root 0 on a 1 um grid -> strip
  auto key = [](const Vec3& p) {
    std::uint64_t k = 0;
    for (int a = 0; a < 3; ++a) k = k * 1000003u + static_cast<std::uint64_t>(std::llround(p[a] * 1e6));
    return k;
  };
  for (std::size_t i = 0; i < strips.size(); ++i) {
    const auto known = first_root.emplace(key(strips[i].points[0]), i);
    if (known.second) continue;
    const Strip& a = strips[known.first->second];
    const Strip& b = strips[i];
    if (a.columns != b.columns || a.rows != b.rows) continue;
    bool same = true;
    for (std::size_t p = 0; p < a.points.size() && same; ++p)
      same = (a.points[p] - b.points[p]).norm() <= 1e-6;
    if (same)
      throw std::invalid_argument(source + ": strips[" + std::to_string(i) +
                                  "]: its points are those of strips[" + std::to_string(known.first->second) +
                                  "] (within 1e-6 m): a strip given twice");
  }
}

}  // namespace hair_sim
