#include "hair_sim/core/model/HairstyleIO.hpp"

#include <cmath>
#include <fstream>
#include <stdexcept>

#include "hair_sim/core/util/YamlReader.hpp"

namespace hair_sim {

namespace {

constexpr double kMaxCoordinate = Hairstyle::kMaxCoordinate;
constexpr double kMaxScalpRadius = Hairstyle::kMaxScalpRadius;

Rgba readColor(const YamlReader& strip) {
  const YamlReader c = strip.child("color");
  if (!c.isSequence() || (c.size() != 3 && c.size() != 4))
    throw c.error("", "expected [r, g, b] or [r, g, b, a] with values in [0, 1]");
  float v[4] = {0.f, 0.f, 0.f, 1.f};
  for (std::size_t i = 0; i < c.size(); ++i) {
    const double x = c.at(i).asDouble();
    if (x < 0.0 || x > 1.0)
      throw c.at(i).error("", "colour channel " + formatDouble(x) + " is outside [0, 1]");
    v[i] = static_cast<float>(x);
  }
  return Rgba{v[0], v[1], v[2], v[3]};
}

}  // namespace

Hairstyle loadHairstyle(const std::string& path) {
  const YamlReader root = YamlReader::loadFile(path);
  root.requireKeys({"format_version", "scalp", "strips"});
  const int version = root.getInt("format_version", 1, 1, 1);
  (void)version;
  Hairstyle style;
  const YamlReader scalp = root.child("scalp");
  scalp.requireKeys({"center", "rpy", "radii"});
  const Vec3 radii = scalp.getVec3("radii");
  for (int i = 0; i < 3; ++i)
    if (!(radii[i] > 0.0 && radii[i] <= kMaxScalpRadius))
      throw scalp.error("radii", "every radius must be in (0, " + formatDouble(kMaxScalpRadius) +
                                     "] m, got " + formatDouble(radii[i]));
  const Vec3 center = scalp.getVec3("center", Vec3::Zero());
  if (!(center.cwiseAbs().maxCoeff() <= kMaxCoordinate))
    throw scalp.error("center", "every coordinate must be within +-" + formatDouble(kMaxCoordinate) +
                                    " m of the head frame's origin");
  style.scalp = Ellipsoid::fromRpy(center, scalp.getRpy("rpy"), radii);

  const YamlReader strips = root.child("strips");
  strips.requireSequence(1);
  style.strips.reserve(strips.size());
  for (std::size_t i = 0; i < strips.size(); ++i) {
    const YamlReader y = strips.at(i);
    y.requireKeys({"name", "columns", "rows", "hair_length", "width", "thickness_margin", "color", "points"});
    Strip s;
    s.name = y.getString("name", "strip" + std::to_string(i));
    s.columns = y.getInt("columns", Strip::kMinColumns, Strip::kMaxColumns);
    s.rows = y.getInt("rows", Strip::kMinRows, Strip::kMaxRows);
    s.hair_length = y.getDouble("hair_length", Strip::kMinHairLength, Strip::kMaxHairLength);
    s.width = y.getDouble("width", Strip::kMinWidth, Strip::kMaxWidth);
    s.thickness_margin = y.getDouble("thickness_margin", 0.0, Strip::kMaxThicknessMargin, s.thickness_margin);
    if (y.has("color")) s.color = readColor(y);
    const YamlReader pts = y.child("points");
    pts.requireSequence();
    if (static_cast<int>(pts.size()) != s.pointCount()) {
      throw pts.error("", std::to_string(pts.size()) +
                              " points given, columns x rows = " + std::to_string(s.columns) + " x " +
                              std::to_string(s.rows) + " = " + std::to_string(s.pointCount()));
    }
    s.points.resize(pts.size());
    for (std::size_t p = 0; p < pts.size(); ++p) {
      s.points[p] = pts.at(p).asVec3();
      if (!(s.points[p].cwiseAbs().maxCoeff() <= kMaxCoordinate))
        throw pts.at(p).error("", "every coordinate must be within +-" + formatDouble(kMaxCoordinate) +
                                      " m of the head frame's origin");
    }
    // validate's checks of one strip (segment lengths, roots on the scalp), here to name the line.
    const Hairstyle::StripProblem problem = style.checkStrip(s);
    if (!problem.key.empty()) {
      if (problem.key == "points" && problem.item >= 0) throw pts.at(problem.item).error("", problem.message);
      throw y.error(problem.key, problem.message);
    }
    style.strips.push_back(std::move(s));
  }
  // The checks above name the line; validate repeats them for hairstyles made in code, and adds those
  // across points and strips (segment lengths, roots on the scalp, a strip given twice).
  style.validate(path);
  return style;
}

void saveHairstyle(const Hairstyle& hairstyle, const std::string& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("saveHairstyle: cannot write '" + path + "'");
  auto vec = [](const Vec3& v) {
    return "[" + formatDouble(v.x()) + ", " + formatDouble(v.y()) + ", " + formatDouble(v.z()) + "]";
  };
  const Ellipsoid& e = hairstyle.scalp;
  const Vec3 rpy = e.rotation().eulerAngles(2, 1, 0).reverse();
  out << "# hair_sim hairstyle (head frame, metres). Row 0 of each strip is the root row on the scalp;\n"
      << "# points are row-major: rows x columns, [x, y, z].\n"
      << "format_version: 1\n"
      << "scalp: {center: " << vec(e.center()) << ", rpy: " << vec(rpy) << ", radii: " << vec(e.radii())
      << "}\n"
      << "strips:\n";
  for (const Strip& s : hairstyle.strips) {
    out << "  - name: " << s.name << "\n"
        << "    columns: " << s.columns << "\n"
        << "    rows: " << s.rows << "\n"
        << "    hair_length: " << formatDouble(s.hair_length) << "\n"
        << "    width: " << formatDouble(s.width) << "\n"
        << "    thickness_margin: " << formatDouble(s.thickness_margin) << "\n"
        << "    color: [" << formatDouble(s.color.r) << ", " << formatDouble(s.color.g) << ", "
        << formatDouble(s.color.b) << ", " << formatDouble(s.color.a) << "]\n"
        << "    points:\n";
    for (const Vec3& p : s.points) out << "      - " << vec(p) << "\n";
  }
  if (!out) throw std::runtime_error("saveHairstyle: error while writing '" + path + "'");
}

}  // namespace hair_sim
