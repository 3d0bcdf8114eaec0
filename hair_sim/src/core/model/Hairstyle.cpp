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
