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

/// "<value> is outside [lo, hi]" unless lo <= value <= hi (NaN is outside), else "".
std::string outside(double value, double lo, double hi) {
  if (value >= lo && value <= hi) return "";
  return formatDouble(value) + " is outside [" + formatDouble(lo) + ", " + formatDouble(hi) + "]";
}

/// "<vec> is not finite" or "... has a coordinate beyond +-100 m of the head frame's origin", else "".
std::string badCoordinates(const Vec3& p) {
  if (!p.allFinite()) return vecString(p) + " is not finite";
  if (p.cwiseAbs().maxCoeff() <= Hairstyle::kMaxCoordinate) return "";
  return vecString(p) + " has a coordinate beyond +-" + formatDouble(Hairstyle::kMaxCoordinate) +
         " m of the head frame's origin";
}

}  // namespace

Hairstyle::StripProblem Hairstyle::checkStrip(const Strip& s, double root_tolerance) const {
  const auto range = [](int lo, int hi) {
    return "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  };
  if (s.columns < Strip::kMinColumns || s.columns > Strip::kMaxColumns)
    return {"columns", -1,
            std::to_string(s.columns) + " is outside " + range(Strip::kMinColumns, Strip::kMaxColumns)};
  if (s.rows < Strip::kMinRows || s.rows > Strip::kMaxRows)
    return {"rows", -1, std::to_string(s.rows) + " is outside " + range(Strip::kMinRows, Strip::kMaxRows)};
  if (static_cast<int>(s.points.size()) != s.pointCount())
    return {"points", -1,
            std::to_string(s.points.size()) +
                " points given, columns x rows = " + std::to_string(s.pointCount())};
  std::string m;
  if (!(m = outside(s.hair_length, Strip::kMinHairLength, Strip::kMaxHairLength)).empty())
    return {"hair_length", -1, m};
  if (!(m = outside(s.width, Strip::kMinWidth, Strip::kMaxWidth)).empty()) return {"width", -1, m};
  if (!(m = outside(s.thickness_margin, 0.0, Strip::kMaxThicknessMargin)).empty())
    return {"thickness_margin", -1, m};
  const float channels[4] = {s.color.r, s.color.g, s.color.b, s.color.a};
  for (int c = 0; c < 4; ++c)
    if (!(m = outside(channels[c], 0.0, 1.0)).empty()) return {"color", c, m};
  for (std::size_t p = 0; p < s.points.size(); ++p)
    if (!(m = badCoordinates(s.points[p])).empty()) return {"points", static_cast<int>(p), m};
  for (int c = 0; c < s.columns; ++c) {
    for (int r = 1; r < s.rows; ++r) {
      const double d = (s.point(r, c) - s.point(r - 1, c)).norm();
      if (d < 1e-4)
        return {"points", s.index(r, c),
                "segment length " + formatDouble(d) + " m to the point above is below 1e-4 m"};
    }
    const Vec3& root = s.point(0, c);
    const double off = (root - scalp.radialProjection(root)).norm();
    if (off > root_tolerance)
      return {"points", c,
              "root " + vecString(root) + " is " + formatDouble(off) + " m off the scalp (tolerance " +
                  formatDouble(root_tolerance) + " m)"};
  }
  return {};
}

void Hairstyle::validate(const std::string& source, double root_tolerance) const {
  const std::string center = badCoordinates(scalp.center());
  if (!center.empty()) throw std::invalid_argument(source + ": scalp.center: " + center);
  for (int a = 0; a < 3; ++a) {
    if (!(scalp.radii()[a] > 0.0 && scalp.radii()[a] <= kMaxScalpRadius))
      throw std::invalid_argument(source + ": scalp.radii: every radius must be in (0, " +
                                  formatDouble(kMaxScalpRadius) + "] m, got " + vecString(scalp.radii()));
  }
  if (strips.empty()) throw std::invalid_argument(source + ": strips: the hairstyle has no strips");
  for (std::size_t i = 0; i < strips.size(); ++i) {
    const StripProblem problem = checkStrip(strips[i], root_tolerance);
    if (problem.key.empty()) continue;
    throw std::invalid_argument(source + ": strips[" + std::to_string(i) + "]." + problem.key +
                                (problem.item >= 0 ? "[" + std::to_string(problem.item) + "]" : "") + ": " +
                                problem.message);
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
