#include "hair_sim/core/geometry/BSplineSurface.hpp"

#include <gtest/gtest.h>

#include "TestUtil.hpp"

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace hair_sim {
namespace {

/// Random curved grid: columns spread along y, rows hanging down z with random offsets (m).
std::vector<Vec3> randomGrid(int columns, int rows, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.03, 0.03);
  std::vector<Vec3> points(static_cast<std::size_t>(columns * rows));
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < columns; ++c) {
      points[static_cast<std::size_t>(r * columns + c)] =
          Vec3(0.01 * r * r + jitter(rng), 0.02 * c + jitter(rng), -0.06 * r + jitter(rng));
    }
  }
  return points;
}

const Vec3& at(const std::vector<Vec3>& grid, int columns, int column, int row) {
  return grid[static_cast<std::size_t>(row * columns + column)];
}

using test::expectInvalid;

TEST(BSplineSurfaceTest, DegreeAcrossFollowsColumnCount) {
  EXPECT_EQ(BSplineSurface::degreeAcross(2), 1);
  EXPECT_EQ(BSplineSurface::degreeAcross(3), 2);
  EXPECT_EQ(BSplineSurface::degreeAcross(4), 3);
  EXPECT_EQ(BSplineSurface::degreeAcross(7), 3);
}

TEST(BSplineSurfaceTest, DeBoorCubicAtKnotIsOneFourOneOverSix) {
  Vec3 points[4] = {Vec3(0, 0, 0), Vec3(6, 0, 0), Vec3(6, 6, 0), Vec3(0, 6, 12)};
  Vec3 derivative;
  const Vec3 value = BSplineSurface::deBoor(points, 3, 0.0, &derivative);
  // (P0 + 4 P1 + P2) / 6 and (P2 - P0) / 2.
  EXPECT_NEAR((value - Vec3(5.0, 1.0, 0.0)).norm(), 0.0, 1e-14);
  EXPECT_NEAR((derivative - Vec3(3.0, 3.0, 0.0)).norm(), 0.0, 1e-14);
  Vec3 again[4] = {Vec3(0, 0, 0), Vec3(6, 0, 0), Vec3(6, 6, 0), Vec3(0, 6, 12)};
  // At t = 1: (P1 + 4 P2 + P3) / 6 = (6 + 24 + 0, 0 + 24 + 6, 12) / 6.
  EXPECT_NEAR((BSplineSurface::deBoor(again, 3, 1.0, nullptr) - Vec3(5.0, 5.0, 2.0)).norm(), 0.0, 1e-14);
}

TEST(BSplineSurfaceTest, DeBoorQuadraticAndLinearClosedForms) {
  // Quadratic uniform basis at t: ((1-t)^2, -2t^2 + 2t + 1, t^2) / 2; at t = 0.5: (1, 6, 1) / 8.
  Vec3 q[3] = {Vec3(8, 0, 0), Vec3(0, 8, 0), Vec3(0, 0, 8)};
  Vec3 dq;
  EXPECT_NEAR((BSplineSurface::deBoor(q, 2, 0.5, &dq) - Vec3(1, 6, 1)).norm(), 0.0, 1e-14);
  // Derivative (-(1-t), 1 - 2t, t) at 0.5: (-4, 0, 4).
  EXPECT_NEAR((dq - Vec3(-4, 0, 4)).norm(), 0.0, 1e-14);
  Vec3 l[2] = {Vec3(1, 2, 3), Vec3(3, 2, 1)};
  Vec3 dl;
  EXPECT_NEAR((BSplineSurface::deBoor(l, 1, 0.25, &dl) - Vec3(1.5, 2, 2.5)).norm(), 0.0, 1e-14);
  EXPECT_NEAR((dl - Vec3(2, 0, -2)).norm(), 0.0, 1e-14);
}

TEST(BSplineSurfaceTest, InteriorKnotAlongHairIsOneFourOneCombination) {
  for (int columns = 2; columns <= 5; ++columns) {
    const int rows = 7;
    const std::vector<Vec3> grid = randomGrid(columns, rows, 11u + columns);
    const BSplineSurface surface(grid, columns, rows);
    for (int j = 1; j <= rows - 2; ++j) {
      const double v = static_cast<double>(j) / (rows - 1);
      // u = 0 is the curve of column 0 whatever the degree across.
      const Vec3 expected =
          (at(grid, columns, 0, j - 1) + 4.0 * at(grid, columns, 0, j) + at(grid, columns, 0, j + 1)) / 6.0;
      EXPECT_NEAR((surface.evaluate(0.0, v) - expected).norm(), 0.0, 1e-12) << columns << " " << j;
      const Vec3 expected_last =
          (at(grid, columns, columns - 1, j - 1) + 4.0 * at(grid, columns, columns - 1, j) +
           at(grid, columns, columns - 1, j + 1)) /
          6.0;
      EXPECT_NEAR((surface.evaluate(1.0, v) - expected_last).norm(), 0.0, 1e-12) << columns << " " << j;
    }
  }
}

TEST(BSplineSurfaceTest, PhantomEndsInterpolateCornersAndAreTangentToEndSegments) {
  for (int columns = 2; columns <= 5; ++columns) {
    for (int rows = 4; rows <= 8; ++rows) {
      const std::vector<Vec3> grid = randomGrid(columns, rows, 100u * columns + rows);
      const BSplineSurface surface(grid, columns, rows);
      for (int side = 0; side < 2; ++side) {
        const int c = side == 0 ? 0 : columns - 1;
        const double u = side;
        Vec3 p;
        Vec3 du;
        Vec3 dv;
        surface.evaluate(u, 0.0, p, du, dv);
        EXPECT_NEAR((p - at(grid, columns, c, 0)).norm(), 0.0, 1e-12);
        // d/dv at the root = (rows - 1) (P1 - P0): tangent to the first segment.
        EXPECT_NEAR((dv - (rows - 1) * (at(grid, columns, c, 1) - at(grid, columns, c, 0))).norm(), 0.0,
                    1e-11);
        surface.evaluate(u, 1.0, p, du, dv);
        EXPECT_NEAR((p - at(grid, columns, c, rows - 1)).norm(), 0.0, 1e-12);
        EXPECT_NEAR(
            (dv - (rows - 1) * (at(grid, columns, c, rows - 1) - at(grid, columns, c, rows - 2))).norm(), 0.0,
            1e-11);
      }
    }
  }
}

TEST(BSplineSurfaceTest, AcrossTheWidthClosedForms) {
  const int rows = 5;
  // Linear (2 columns): S(u, v) = (1 - u) C0(v) + u C1(v).
  {
    const std::vector<Vec3> grid = randomGrid(2, rows, 7u);
    const BSplineSurface surface(grid, 2, rows);
    for (double v : {0.0, 0.3, 0.77, 1.0}) {
      const Vec3 c0 = surface.evaluate(0.0, v);
      const Vec3 c1 = surface.evaluate(1.0, v);
      for (double u : {0.0, 0.25, 0.6, 1.0}) {
        EXPECT_NEAR((surface.evaluate(u, v) - ((1 - u) * c0 + u * c1)).norm(), 0.0, 1e-12);
      }
    }
  }
  // Quadratic (3 columns), root row: at u = 1/2 the middle control point's piece at its centre, weights
  // (1, 6, 1) / 8; at u = 1/4 the straight half piece: the midpoint of P0 and P1 ... at x = 0.5 it is
  // (P0 + P1) / 2 (the knot between the first and the middle piece).
  {
    const std::vector<Vec3> grid = randomGrid(3, rows, 8u);
    const BSplineSurface surface(grid, 3, rows);
    const Vec3& p0 = at(grid, 3, 0, 0);
    const Vec3& p1 = at(grid, 3, 1, 0);
    const Vec3& p2 = at(grid, 3, 2, 0);
    EXPECT_NEAR((surface.evaluate(0.5, 0.0) - (p0 + 6.0 * p1 + p2) / 8.0).norm(), 0.0, 1e-12);
    EXPECT_NEAR((surface.evaluate(0.25, 0.0) - 0.5 * (p0 + p1)).norm(), 0.0, 1e-12);
    EXPECT_NEAR((surface.evaluate(0.125, 0.0) - 0.5 * (p0 + 0.5 * (p0 + p1))).norm(), 0.0, 1e-12);
  }
  // Cubic (4 columns), root row: at u = 1/3 (knot of column 1): (P0 + 4 P1 + P2) / 6.
  {
    const std::vector<Vec3> grid = randomGrid(4, rows, 9u);
    const BSplineSurface surface(grid, 4, rows);
    const Vec3 expected = (at(grid, 4, 0, 0) + 4.0 * at(grid, 4, 1, 0) + at(grid, 4, 2, 0)) / 6.0;
    EXPECT_NEAR((surface.evaluate(1.0 / 3.0, 0.0) - expected).norm(), 0.0, 1e-12);
  }
}

TEST(BSplineSurfaceTest, StraightEquallySpacedChainIsTheLineWithItsPolygonLength) {
  const int rows = 6;
  const double spacing = 0.07;
  const Vec3 direction = Vec3(0.3, -0.2, -1.0).normalized();
  for (int columns = 2; columns <= 4; ++columns) {
    std::vector<Vec3> grid(static_cast<std::size_t>(columns * rows));
    for (int r = 0; r < rows; ++r) {
      for (int c = 0; c < columns; ++c) {
        grid[static_cast<std::size_t>(r * columns + c)] = Vec3(0.0, 0.015 * c, 0.1) + r * spacing * direction;
      }
    }
    const BSplineSurface surface(grid, columns, rows);
    const double polygon_length = (rows - 1) * spacing;
    for (double u : {0.0, 0.4, 1.0}) {
      const Vec3 root = surface.evaluate(u, 0.0);
      double length = 0.0;
      Vec3 previous = root;
      const int samples = 1000;
      for (int i = 0; i <= samples; ++i) {
        const double v = static_cast<double>(i) / samples;
        const Vec3 p = surface.evaluate(u, v);
        // Linear precision: the point is on the line at arc length v * polygon length.
        EXPECT_NEAR((p - (root + v * polygon_length * direction)).norm(), 0.0, 1e-12);
        length += (p - previous).norm();
        previous = p;
      }
      EXPECT_NEAR(length, polygon_length, 1e-9);
    }
  }
}

TEST(BSplineSurfaceTest, DerivativesMatchFiniteDifferences) {
  for (int columns = 2; columns <= 5; ++columns) {
    const int rows = 6;
    const std::vector<Vec3> grid = randomGrid(columns, rows, 300u + columns);
    const BSplineSurface surface(grid, columns, rows);
    const double h = 1e-6;
    for (double u : {0.1, 0.37, 0.5, 0.81}) {
      for (double v : {0.05, 0.33, 0.5, 0.9}) {
        Vec3 p;
        Vec3 du;
        Vec3 dv;
        surface.evaluate(u, v, p, du, dv);
        const Vec3 du_fd = (surface.evaluate(u + h, v) - surface.evaluate(u - h, v)) / (2 * h);
        const Vec3 dv_fd = (surface.evaluate(u, v + h) - surface.evaluate(u, v - h)) / (2 * h);
        EXPECT_NEAR((du - du_fd).norm(), 0.0, 1e-6 * (1.0 + du.norm())) << columns << " " << u << " " << v;
        EXPECT_NEAR((dv - dv_fd).norm(), 0.0, 1e-6 * (1.0 + dv.norm())) << columns << " " << u << " " << v;
      }
    }
  }
}

TEST(BSplineSurfaceTest, SurfaceIsContinuousAcrossSpanBoundaries) {
  for (int columns = 2; columns <= 5; ++columns) {
    const int rows = 6;
    const std::vector<Vec3> grid = randomGrid(columns, rows, 500u + columns);
    const BSplineSurface surface(grid, columns, rows);
    const double eps = 1e-9;
    for (int i = 1; i < columns - 1; ++i) {  // cubic/linear knots and, for 3 columns, the control point
      for (double offset : {0.0, 0.5}) {
        const double u = (i + offset - 0.5 * (columns == 3 ? 1 : 0)) / (columns - 1);
        if (u <= eps || u >= 1 - eps) {
          continue;
        }
        EXPECT_NEAR((surface.evaluate(u - eps, 0.4) - surface.evaluate(u + eps, 0.4)).norm(), 0.0, 1e-8);
      }
    }
    for (int j = 1; j < rows - 1; ++j) {
      const double v = static_cast<double>(j) / (rows - 1);
      EXPECT_NEAR((surface.evaluate(0.3, v - eps) - surface.evaluate(0.3, v + eps)).norm(), 0.0, 1e-8);
    }
  }
}

TEST(BSplineSurfaceTest, ExtendedControlPointsAreReflections) {
  const std::vector<Vec3> grid = randomGrid(3, 5, 42u);
  const BSplineSurface surface(grid, 3, 5);
  EXPECT_EQ(surface.controlPoint(2, 4), at(grid, 3, 2, 4));
  EXPECT_NEAR((surface.extendedControlPoint(0, -1) - (2 * at(grid, 3, 0, 0) - at(grid, 3, 0, 1))).norm(), 0.0,
              1e-15);
  EXPECT_NEAR((surface.extendedControlPoint(3, 2) - (2 * at(grid, 3, 2, 2) - at(grid, 3, 1, 2))).norm(), 0.0,
              1e-15);
  const Vec3 corner =
      2 * (2 * at(grid, 3, 0, 0) - at(grid, 3, 1, 0)) - (2 * at(grid, 3, 0, 1) - at(grid, 3, 1, 1));
  EXPECT_NEAR((surface.extendedControlPoint(-1, -1) - corner).norm(), 0.0, 1e-15);
  test::expectThrowNaming<std::out_of_range>(
      [&] { surface.extendedControlPoint(-2, 0); },
      "(column -2, row 0) outside the extended grid [-1, 3] x [-1, 5]");
  test::expectThrowNaming<std::out_of_range>([&] { surface.controlPoint(3, 0); },
                                             "(column 3, row 0) outside the 3 x 5 grid");
}

TEST(BSplineSurfaceTest, BadInputsThrowNamingTheValue) {
  const std::vector<Vec3> grid = randomGrid(2, 5, 1u);
  expectInvalid([&] { BSplineSurface s(grid.data(), 1, 5); }, "columns must be >= 2, got 1");
  expectInvalid([&] { BSplineSurface s(grid.data(), 2, 3); }, "rows must be >= 4, got 3");
  expectInvalid([&] { BSplineSurface s(static_cast<const Vec3*>(nullptr), 2, 5); }, "null");
  expectInvalid([&] { BSplineSurface s(grid, 2, 4); }, "10 points, columns * rows = 8");
  std::vector<Vec3> bad = grid;
  bad[7].y() = std::numeric_limits<double>::quiet_NaN();
  expectInvalid([&] { BSplineSurface s(bad, 2, 5); }, "control point 7 (column 1, row 3) is not finite");
  const BSplineSurface surface(grid, 2, 5);
  expectInvalid([&] { surface.evaluate(1.5, 0.2); }, "got (1.500000, 0.200000)");
  expectInvalid([&] { surface.evaluate(0.5, -0.1); }, "got (0.500000, -0.100000)");
  expectInvalid([&] { surface.evaluate(std::numeric_limits<double>::quiet_NaN(), 0.2); }, "nan");
}

}  // namespace
}  // namespace hair_sim
