#pragma once
/// Shared helpers and tolerances of the core tests.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "hair_sim/core/model/Body.hpp"
#include "hair_sim/core/model/Hairstyle.hpp"

namespace hair_sim {
namespace test {

constexpr double kPi = 3.14159265358979323846;

inline std::string repoPath(const std::string& relative) {
  return std::string(HAIR_SIM_REPO_ROOT) + "/" + relative;
}

/// A path for a scratch file `name` under the test's temp folder, removed when the test program ends.
inline std::string tempPath(const std::string& name) {
  // Removes the files when the program exits normally (a crashed test leaves its files for a look).
  struct Remover {
    std::vector<std::string> paths;
    ~Remover() {
      for (const std::string& p : paths) std::remove(p.c_str());
    }
  };
  static Remover remover;
  // The process id in the name: CTest runs test executables in parallel, and they share TempDir().
  const std::string path = ::testing::TempDir() + "hair_sim_" + std::to_string(::getpid()) + "_" + name;
  remover.paths.push_back(path);
  return path;
}

/// Writes text to a fresh file under the test's temp folder (tempPath) and returns its path.
inline std::string writeTemp(const std::string& name, const std::string& text) {
  const std::string path = tempPath(name);
  std::ofstream out(path);
  out << text;
  return path;
}

/// The angle (rad, in [0, pi]) between two directions, well conditioned at small angles.
inline double angleBetween(const Vec3& a, const Vec3& b) { return std::atan2(a.cross(b).norm(), a.dot(b)); }

/// A hairstyle of one strip with `columns` straight columns of `rows` points hanging from the top of
/// a sphere of radius 0.1 m, each segment of length d, tilted by `tilt` rad about +x from straight down.
/// (The chain hangs through the sphere: these tests have no collision bodies.)
inline Hairstyle hangingStrip(int columns, int rows, double d, double tilt, double spacing = 0.01) {
  Hairstyle style;
  style.scalp = Ellipsoid(Vec3::Zero(), Mat3::Identity(), Vec3(0.1, 0.1, 0.1));
  Strip s;
  s.columns = columns;
  s.rows = rows;
  s.hair_length = d * (rows - 1);
  s.width = spacing * (columns - 1) + 1e-3;
  s.points.resize(static_cast<std::size_t>(columns * rows));
  const Vec3 dir(0.0, std::sin(tilt), -std::cos(tilt));  // rotation about +x of (0,0,-1)
  for (int c = 0; c < columns; ++c) {
    const double y = spacing * (c - 0.5 * (columns - 1));
    const Vec3 root(0.0, y, std::sqrt(0.01 - y * y));
    for (int r = 0; r < rows; ++r) s.point(r, c) = root + r * d * dir;
  }
  style.strips.push_back(s);
  return style;
}

/// Six spheres in the world frame on the axes about o (centres o +- c e_i) of radius `negative` on the
/// negative axes and `positive` on the positive ones: a pinch for the segments hung from points near o when
/// every end at their length lies inside one.
inline std::vector<Body> axisBalls(const Vec3& o, double c, double negative, double positive) {
  std::vector<Body> bodies;
  for (int axis = 0; axis < 3; ++axis)
    for (double sign : {-1.0, 1.0})
      bodies.push_back(Body{"ball", "world",
                            Ellipsoid(o + sign * c * Vec3::Unit(axis), Mat3::Identity(),
                                      Vec3::Constant(sign > 0.0 ? positive : negative))});
  return bodies;
}

/// Every strip's control points in one array, strip by strip (the Simulator's order, positionsHead()); each
/// strip's first index into `offsets` when given.
inline std::vector<Vec3> styledPoints(const Hairstyle& style, std::vector<int>* offsets = nullptr) {
  std::vector<Vec3> points;
  if (offsets) offsets->clear();
  for (const Strip& s : style.strips) {
    if (offsets) offsets->push_back(static_cast<int>(points.size()));
    points.insert(points.end(), s.points.begin(), s.points.end());
  }
  return points;
}

/// How far the deepest control point below the roots lies inside a body inflated by its strip's thickness
/// margin (m; 0: none inside), from the geometry alone, without the Simulator's bodies or counters: each
/// point (head frame, `points`, strip by strip as `offsets`) taken to the world by `head_pose`, into body
/// b's frame by body_frames[b] and into its shape's axes, then against the radii + margin. The depth is
/// (1 - |q|) times the smallest radius, q the point in the unit sphere's space: no more than the true depth.
inline double deepestInside(const std::vector<Vec3>& points, const std::vector<int>& offsets,
                            const Hairstyle& style, const std::vector<Body>& bodies, const Iso3& head_pose,
                            const std::vector<Iso3>& body_frames) {
  double worst = 0.0;
  for (std::size_t s = 0; s < style.strips.size(); ++s) {
    const Strip& strip = style.strips[s];
    for (int p = strip.columns; p < strip.pointCount(); ++p) {  // row 0: the roots, on the scalp
      const Vec3 world = head_pose * points[static_cast<std::size_t>(offsets[s] + p)];
      for (std::size_t b = 0; b < bodies.size(); ++b) {
        const Ellipsoid& shape = bodies[b].shape;
        const Vec3 radii = shape.radii().array() + strip.thickness_margin;
        const Vec3 local = shape.rotation().transpose() * (body_frames[b].inverse() * world - shape.center());
        const double q = local.cwiseQuotient(radii).norm();
        if (q < 1.0) worst = std::max(worst, (1.0 - q) * radii.minCoeff());
      }
    }
  }
  return worst;
}

/// Runs f and returns the std::invalid_argument message it throws (fails the test if none).
template <typename F>
std::string errorOf(F f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected std::invalid_argument";
  return "";
}

/// One malformed edit of a good file: `from` replaced by `to`; the error must name `key` and `value`.
struct FileEdit {
  const char* from;
  const char* to;
  const char* key;
  const char* value;
};

/// For every edit: writes the edited text to a fresh file, calls load(path) and expects a
/// std::invalid_argument whose message names the file, the key and the value.
template <typename Load>
void expectEditsNamed(const std::string& good, const std::vector<FileEdit>& edits, Load load) {
  for (const FileEdit& e : edits) {
    std::string text = good;
    const std::size_t at = text.find(e.from);
    ASSERT_NE(at, std::string::npos) << e.from;
    text.replace(at, std::string(e.from).size(), e.to);
    const std::string path = writeTemp("edited.yaml", text);
    const std::string m = errorOf([&] { load(path); });
    EXPECT_NE(m.find(path), std::string::npos) << "edit '" << e.to << "': " << m;
    EXPECT_NE(m.find(e.key), std::string::npos) << "edit '" << e.to << "': " << m;
    EXPECT_NE(m.find(e.value), std::string::npos) << "edit '" << e.to << "': " << m;
  }
}

/// Expects `statement` to throw an E whose message contains `text`.
template <typename E, typename F>
void expectThrowNaming(F statement, const std::string& text) {
  try {
    statement();
    ADD_FAILURE() << "no exception, expected one mentioning '" << text << "'";
  } catch (const E& e) {
    EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
  }
}

/// Expects `statement` to throw std::invalid_argument whose message contains `text`.
template <typename F>
void expectInvalid(F statement, const std::string& text) {
  expectThrowNaming<std::invalid_argument>(statement, text);
}

}  // namespace test
}  // namespace hair_sim
