#include "hair_sim/core/geometry/Tessellator.hpp"

#include <gtest/gtest.h>

#include "TestUtil.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "hair_sim/core/geometry/BSplineSurface.hpp"
#include "hair_sim/core/model/HairstyleIO.hpp"

namespace hair_sim {
namespace {

constexpr TessellationMethod kMethods[] = {TessellationMethod::ForwardDifferencing,
                                           TessellationMethod::DeBoor, TessellationMethod::CachedBasis};

/// Curved random strip: each column is a chain of `segment` long links bending with random angles.
std::vector<Vec3> curvedGrid(int columns, int rows, unsigned seed, double segment = 0.08) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> angle(-0.6, 0.6);
  std::uniform_real_distribution<double> offset(-0.004, 0.004);
  std::vector<Vec3> points(static_cast<std::size_t>(columns * rows));
  std::vector<double> bends(static_cast<std::size_t>(rows));
  for (double& b : bends) {
    b = angle(rng);
  }
  for (int c = 0; c < columns; ++c) {
    Vec3 p(offset(rng), 0.015 * c + offset(rng), offset(rng));
    double pitch = 0.3;
    for (int r = 0; r < rows; ++r) {
      points[static_cast<std::size_t>(r * columns + c)] = p;
      pitch += bends[static_cast<std::size_t>(r)] + 0.3 * angle(rng);
      const double yaw = 0.4 * angle(rng);
      p += segment * Vec3(std::cos(pitch) * std::cos(yaw), std::sin(yaw), -std::sin(pitch)).normalized();
    }
  }
  return points;
}

/// Length of the de Boor curve at u (dense polyline).
double curveLength(const BSplineSurface& surface, double u) {
  double length = 0.0;
  Vec3 previous = surface.evaluate(u, 0.0);
  for (int i = 1; i <= 4000; ++i) {
    const Vec3 p = surface.evaluate(u, i / 4000.0);
    length += (p - previous).norm();
    previous = p;
  }
  return length;
}

double columnLength(const StripMesh& mesh, int iu) {
  double length = 0.0;
  for (int iv = 1; iv < mesh.n_v; ++iv) {
    length += (mesh.positions[static_cast<std::size_t>(mesh.index(iu, iv))] -
               mesh.positions[static_cast<std::size_t>(mesh.index(iu, iv - 1))])
                  .norm();
  }
  return length;
}

double maxPositionDifference(const StripMesh& a, const StripMesh& b) {
  double worst = 0.0;
  for (std::size_t i = 0; i < a.positions.size(); ++i) {
    worst = std::max(worst, (a.positions[i] - b.positions[i]).norm());
  }
  return worst;
}

using test::expectInvalid;

TEST(TessellatorTest, DefaultsAndNames) {
  const Tessellator tessellator;
  EXPECT_EQ(tessellator.method(), TessellationMethod::CachedBasis);
  EXPECT_EQ(tessellator.levelOfDetail().samples_across, 2);
  EXPECT_EQ(tessellator.levelOfDetail().samples_along, 4);
  EXPECT_STREQ(Tessellator::methodName(TessellationMethod::ForwardDifferencing), "ForwardDifferencing");
  EXPECT_STREQ(Tessellator::methodName(TessellationMethod::DeBoor), "DeBoor");
  EXPECT_STREQ(Tessellator::methodName(TessellationMethod::CachedBasis), "CachedBasis");
}

TEST(TessellatorTest, VertexAndTriangleCounts) {
  // Paper strip 2 x 5 at the default (2, 4): n_u = 3, n_v = 17, 2 * 2 * 16 = 64 triangles.
  const LevelOfDetail level;
  EXPECT_EQ(Tessellator::verticesAcross(2, level), 3);
  EXPECT_EQ(Tessellator::verticesAlong(5, level), 17);
  EXPECT_EQ(Tessellator::triangleCount(StripShape{2, 5}, level), 64);
  EXPECT_EQ(Tessellator::triangleCount(StripShape{4, 6}, LevelOfDetail{3, 2}), 2 * 9 * 10);
  EXPECT_EQ(Tessellator::triangleCount(std::vector<StripShape>(100, StripShape{2, 5}), level), 6400);

  Tessellator tessellator(LevelOfDetail{3, 2});
  StripMesh mesh;
  tessellator.tessellate(curvedGrid(4, 6, 1u), 4, 6, 10.0, mesh);
  EXPECT_EQ(mesh.n_u, 10);
  EXPECT_EQ(mesh.n_v, 11);
  EXPECT_EQ(mesh.vertexCount(), 110);
  EXPECT_EQ(mesh.positions.size(), 110u);
  EXPECT_EQ(mesh.normals.size(), 110u);
  EXPECT_EQ(mesh.tangents.size(), 110u);
  EXPECT_EQ(mesh.v_param.size(), 110u);
  EXPECT_EQ(mesh.u_param.size(), 110u);
  EXPECT_EQ(mesh.triangleCount(), 180);

  std::vector<std::uint32_t> indices;
  Tessellator::appendTriangles(mesh, 0, false, indices);
  EXPECT_EQ(indices.size(), 3u * 180u);
  for (std::uint32_t index : indices) {
    EXPECT_LT(index, 110u);
  }
  // First cell: (0,0) (1,0) (0,1) and (1,0) (1,1) (0,1).
  EXPECT_EQ(indices[0], 0u);
  EXPECT_EQ(indices[1], 1u);
  EXPECT_EQ(indices[2], 10u);
  EXPECT_EQ(indices[3], 1u);
  EXPECT_EQ(indices[4], 11u);
  EXPECT_EQ(indices[5], 10u);
  std::vector<std::uint32_t> both;
  Tessellator::appendTriangles(mesh, 7, true, both);
  ASSERT_EQ(both.size(), 6u * 180u);
  EXPECT_EQ(both[0], 7u);
  EXPECT_EQ(both[3], 7u);  // flipped copy (a, c, b)
  EXPECT_EQ(both[4], 17u);
  EXPECT_EQ(both[5], 8u);
}

TEST(TessellatorTest, FrontWindingAgreesWithNormals) {
  // Smooth strip (no fold): 3 columns along y, rows bending from +x down to -z.
  std::vector<Vec3> grid(15);
  for (int r = 0; r < 5; ++r) {
    for (int c = 0; c < 3; ++c) {
      const double angle = 0.35 * r;
      grid[static_cast<std::size_t>(3 * r + c)] =
          Vec3(0.2 * std::sin(angle), 0.02 * c + 0.005 * r * c, 0.2 * (std::cos(angle) - 1.0));
    }
  }
  Tessellator tessellator;
  StripMesh mesh;
  tessellator.tessellate(grid, 3, 5, 10.0, mesh);
  std::vector<std::uint32_t> indices;
  Tessellator::appendTriangles(mesh, 0, false, indices);
  for (std::size_t t = 0; t < indices.size(); t += 3) {
    const Vec3& a = mesh.positions[indices[t]];
    const Vec3 face = (mesh.positions[indices[t + 1]] - a).cross(mesh.positions[indices[t + 2]] - a);
    EXPECT_GT(face.dot(mesh.normals[indices[t]]), 0.0) << t;
  }
}

/// Forward differencing and the cached basis against de Boor at every level of detail 1..8 x 1..8,
/// columns 2..5, rows 4..8, with and without clipping.
TEST(TessellatorTest, AllMethodsAgreeWithDeBoorAtEveryLevelOfDetail) {
  Tessellator reference(LevelOfDetail{}, TessellationMethod::DeBoor);
  Tessellator forward(LevelOfDetail{}, TessellationMethod::ForwardDifferencing);
  Tessellator cached(LevelOfDetail{}, TessellationMethod::CachedBasis);
  StripMesh expected;
  StripMesh mesh_fd;
  StripMesh mesh_cb;
  double worst_fd = 0.0;
  double worst_cb = 0.0;
  int clipped_columns = 0;
  for (int columns = 2; columns <= 5; ++columns) {
    for (int rows = 4; rows <= 8; ++rows) {
      const std::vector<Vec3> grid = curvedGrid(columns, rows, 1000u * columns + rows);
      const BSplineSurface surface(grid, columns, rows);
      const double length = curveLength(surface, 0.0);
      for (double hair_length : {10.0, 0.6 * length}) {
        for (int across = 1; across <= 8; ++across) {
          for (int along = 1; along <= 8; ++along) {
            const LevelOfDetail level{across, along};
            reference.setLevelOfDetail(level);
            forward.setLevelOfDetail(level);
            cached.setLevelOfDetail(level);
            reference.tessellate(grid, columns, rows, hair_length, expected);
            forward.tessellate(grid, columns, rows, hair_length, mesh_fd);
            cached.tessellate(grid, columns, rows, hair_length, mesh_cb);
            ASSERT_EQ(mesh_fd.vertexCount(), expected.vertexCount());
            ASSERT_EQ(mesh_cb.vertexCount(), expected.vertexCount());
            worst_fd = std::max(worst_fd, maxPositionDifference(mesh_fd, expected));
            worst_cb = std::max(worst_cb, maxPositionDifference(mesh_cb, expected));
            for (std::size_t i = 0; i < expected.positions.size(); ++i) {
              ASSERT_NEAR((mesh_fd.normals[i] - expected.normals[i]).norm(), 0.0, 1e-7) << i;
              ASSERT_NEAR((mesh_cb.normals[i] - expected.normals[i]).norm(), 0.0, 1e-7) << i;
              ASSERT_NEAR((mesh_fd.tangents[i] - expected.tangents[i]).norm(), 0.0, 1e-7) << i;
              ASSERT_NEAR((mesh_cb.tangents[i] - expected.tangents[i]).norm(), 0.0, 1e-7) << i;
              ASSERT_NEAR(mesh_fd.v_param[i], expected.v_param[i], 1e-6f) << i;
              ASSERT_NEAR(mesh_cb.v_param[i], expected.v_param[i], 1e-6f) << i;
            }
            if (hair_length < 10.0) {
              for (int iu = 0; iu < expected.n_u; ++iu) {
                clipped_columns +=
                    expected.v_param[static_cast<std::size_t>(expected.index(iu, expected.n_v - 1))] == 1.0f;
              }
            }
          }
        }
      }
    }
  }
  EXPECT_LE(worst_fd, 1e-9);
  EXPECT_LE(worst_cb, 1e-9);
  EXPECT_GT(clipped_columns, 1000);  // the clipped cases really clip
}

/// Unclipped vertices are the surface points at the sample parameters, with its analytic frame.
TEST(TessellatorTest, VerticesAreSurfacePointsWithTheirFrames) {
  for (TessellationMethod method : kMethods) {
    for (int columns = 2; columns <= 5; ++columns) {
      const int rows = 6;
      const std::vector<Vec3> grid = curvedGrid(columns, rows, 77u + columns);
      const BSplineSurface surface(grid, columns, rows);
      const LevelOfDetail level{3, 5};
      Tessellator tessellator(level, method);
      StripMesh mesh;
      tessellator.tessellate(grid, columns, rows, 10.0, mesh);
      for (int iv = 0; iv < mesh.n_v; ++iv) {
        for (int iu = 0; iu < mesh.n_u; ++iu) {
          const double u = static_cast<double>(iu) / (mesh.n_u - 1);
          const double v = static_cast<double>(iv) / (mesh.n_v - 1);
          Vec3 p;
          Vec3 du;
          Vec3 dv;
          surface.evaluate(u, v, p, du, dv);
          const std::size_t i = static_cast<std::size_t>(mesh.index(iu, iv));
          EXPECT_NEAR((mesh.positions[i] - p).norm(), 0.0, 1e-9);
          EXPECT_NEAR((mesh.normals[i] - du.cross(dv).normalized()).norm(), 0.0, 1e-9);
          EXPECT_NEAR((mesh.tangents[i] - dv.normalized()).norm(), 0.0, 1e-9);
          EXPECT_NEAR(mesh.normals[i].norm(), 1.0, 1e-12);
          EXPECT_NEAR(mesh.tangents[i].norm(), 1.0, 1e-12);
          EXPECT_FLOAT_EQ(mesh.u_param[i], static_cast<float>(u));
        }
      }
    }
  }
}

TEST(TessellatorTest, RootEdgeIsTheRootRowCurve) {
  for (TessellationMethod method : kMethods) {
    // 2 columns: the root edge is the segment between the two root control points.
    {
      const std::vector<Vec3> grid = curvedGrid(2, 5, 5u);
      Tessellator tessellator(LevelOfDetail{4, 4}, method);
      StripMesh mesh;
      tessellator.tessellate(grid, 2, 5, 10.0, mesh);
      for (int iu = 0; iu < mesh.n_u; ++iu) {
        const double u = iu / 4.0;
        EXPECT_NEAR((mesh.positions[static_cast<std::size_t>(iu)] - ((1 - u) * grid[0] + u * grid[1])).norm(),
                    0.0, 1e-12);
        EXPECT_EQ(mesh.v_param[static_cast<std::size_t>(iu)], 0.0f);
      }
    }
    // 4 columns: corners are the root control points, iu = 2 (u = 1/3, a knot) is (P0 + 4 P1 + P2) / 6.
    {
      const std::vector<Vec3> grid = curvedGrid(4, 5, 6u);
      Tessellator tessellator(LevelOfDetail{2, 3}, method);
      StripMesh mesh;
      tessellator.tessellate(grid, 4, 5, 10.0, mesh);
      EXPECT_NEAR((mesh.positions[0] - grid[0]).norm(), 0.0, 1e-12);
      EXPECT_NEAR((mesh.positions[6] - grid[3]).norm(), 0.0, 1e-12);
      EXPECT_NEAR((mesh.positions[2] - (grid[0] + 4.0 * grid[1] + grid[2]) / 6.0).norm(), 0.0, 1e-12);
    }
  }
}

TEST(TessellatorTest, ClippedColumnsHaveExactlyTheHairLength) {
  for (TessellationMethod method : kMethods) {
    for (int columns = 2; columns <= 5; ++columns) {
      const int rows = 7;
      const std::vector<Vec3> grid = curvedGrid(columns, rows, 900u + columns);
      const BSplineSurface surface(grid, columns, rows);
      double shortest = std::numeric_limits<double>::infinity();
      for (double u : {0.0, 0.25, 0.5, 0.75, 1.0}) {
        shortest = std::min(shortest, curveLength(surface, u));
      }
      const double hair_length = 0.8 * shortest;
      Tessellator tessellator(LevelOfDetail{2, 4}, method);
      StripMesh mesh, unclipped;
      tessellator.tessellate(grid, columns, rows, hair_length, mesh);
      tessellator.tessellate(grid, columns, rows, 1e3, unclipped);
      ASSERT_EQ(unclipped.n_u, mesh.n_u);
      for (int iu = 0; iu < mesh.n_u; ++iu) {
        EXPECT_NEAR(columnLength(mesh, iu), hair_length, 1e-9) << iu;
        const std::size_t tip = static_cast<std::size_t>(mesh.index(iu, mesh.n_v - 1));
        EXPECT_EQ(mesh.v_param[tip], 1.0f);
        // Every vertex, the clipped tip among them, lies on the polyline of the unclipped samples.
        for (int iv = 0; iv < mesh.n_v; ++iv) {
          const Vec3& x = mesh.positions[static_cast<std::size_t>(mesh.index(iu, iv))];
          double nearest = std::numeric_limits<double>::infinity();
          for (int jv = 1; jv < unclipped.n_v; ++jv) {
            const Vec3& a = unclipped.positions[static_cast<std::size_t>(unclipped.index(iu, jv - 1))];
            const Vec3& b = unclipped.positions[static_cast<std::size_t>(unclipped.index(iu, jv))];
            const double t = std::clamp((x - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
            nearest = std::min(nearest, (a + t * (b - a) - x).norm());
          }
          EXPECT_LT(nearest, 1e-12) << "column " << iu << ", vertex " << iv;
        }
        float previous = -1.0f;
        for (int iv = 0; iv < mesh.n_v; ++iv) {
          const float v = mesh.v_param[static_cast<std::size_t>(mesh.index(iu, iv))];
          EXPECT_GE(v, previous);
          previous = v;
        }
      }
    }
  }
}

TEST(TessellatorTest, LongHairKeepsTheCurveEndWithoutExtrapolation) {
  for (TessellationMethod method : kMethods) {
    const std::vector<Vec3> grid = curvedGrid(3, 6, 31u);
    const BSplineSurface surface(grid, 3, 6);
    Tessellator tessellator(LevelOfDetail{2, 4}, method);
    StripMesh mesh;
    const double hair_length = 5.0;
    tessellator.tessellate(grid, 3, 6, hair_length, mesh);
    for (int iu = 0; iu < mesh.n_u; ++iu) {
      const double u = static_cast<double>(iu) / (mesh.n_u - 1);
      const std::size_t tip = static_cast<std::size_t>(mesh.index(iu, mesh.n_v - 1));
      EXPECT_NEAR((mesh.positions[tip] - surface.evaluate(u, 1.0)).norm(), 0.0, 1e-9);
      EXPECT_NEAR(mesh.v_param[tip], columnLength(mesh, iu) / hair_length, 1e-6);
      EXPECT_LT(mesh.v_param[tip], 1.0f);
    }
    // The tip row of the outer columns is the tip control point (phantom end condition).
    EXPECT_NEAR((mesh.positions[static_cast<std::size_t>(mesh.index(0, mesh.n_v - 1))] - grid[15]).norm(),
                0.0, 1e-12);
  }
}

TEST(TessellatorTest, StraightChainColumnLengthEqualsHairLength) {
  // Equally spaced straight columns: the curve is the control polygon, its length the hair length.
  const int rows = 5;
  const double spacing = 0.075;
  const Vec3 direction = Vec3(0.2, 0.1, -1.0).normalized();
  std::vector<Vec3> grid(2 * rows);
  for (int r = 0; r < rows; ++r) {
    grid[static_cast<std::size_t>(2 * r)] = r * spacing * direction;
    grid[static_cast<std::size_t>(2 * r + 1)] = Vec3(0.0, 0.02, 0.0) + r * spacing * direction;
  }
  const double hair_length = (rows - 1) * spacing;
  for (TessellationMethod method : kMethods) {
    Tessellator tessellator(LevelOfDetail{2, 4}, method);
    StripMesh mesh;
    tessellator.tessellate(grid, 2, rows, hair_length, mesh);
    for (int iu = 0; iu < mesh.n_u; ++iu) {
      EXPECT_NEAR(columnLength(mesh, iu), hair_length, 1e-9);
      for (int iv = 0; iv < mesh.n_v; ++iv) {
        const std::size_t i = static_cast<std::size_t>(mesh.index(iu, iv));
        // Equal spacing along the line: arc length fraction iv / (n_v - 1).
        EXPECT_NEAR(mesh.v_param[i], static_cast<float>(iv) / (mesh.n_v - 1), 1e-6);
        EXPECT_NEAR((mesh.tangents[i] - direction).norm(), 0.0, 1e-12);
      }
    }
  }
}

TEST(TessellatorTest, ColumnLengthWithinOnePercentOfHairLengthForTypicalStrips) {
  // Strips whose control polygon length is the hair length: the smooth curve cuts corners, so it is a
  // little shorter; the tessellated columns must still be within 1 % of the hair length.
  for (TessellationMethod method : kMethods) {
    const int rows = 5;
    const double segment = 0.08;
    std::vector<Vec3> grid(2 * rows);
    for (int c = 0; c < 2; ++c) {
      Vec3 p(0.0, 0.02 * c, 0.0);
      for (int r = 0; r < rows; ++r) {
        grid[static_cast<std::size_t>(2 * r + c)] = p;
        const double bend = 0.2 + 0.15 * r;
        p += segment * Vec3(std::cos(bend), 0.0, -std::sin(bend));
      }
    }
    Tessellator tessellator(LevelOfDetail{2, 4}, method);
    StripMesh mesh;
    const double hair_length = (rows - 1) * segment;
    tessellator.tessellate(grid, 2, rows, hair_length, mesh);
    for (int iu = 0; iu < mesh.n_u; ++iu) {
      EXPECT_NEAR(columnLength(mesh, iu), hair_length, 0.01 * hair_length);
    }
  }
}

TEST(TessellatorTest, DegenerateStripGivesFiniteUnitFrames) {
  std::vector<Vec3> grid(2 * 4, Vec3(0.1, 0.2, 0.3));  // every control point at the same place
  for (TessellationMethod method : kMethods) {
    Tessellator tessellator(LevelOfDetail{2, 2}, method);
    StripMesh mesh;
    tessellator.tessellate(grid, 2, 4, 0.3, mesh);
    for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
      EXPECT_NEAR((mesh.positions[i] - grid[0]).norm(), 0.0, 1e-15);
      EXPECT_NEAR(mesh.normals[i].norm(), 1.0, 1e-12);
      EXPECT_NEAR(mesh.tangents[i].norm(), 1.0, 1e-12);
      EXPECT_NEAR(mesh.normals[i].dot(mesh.tangents[i]), 0.0, 1e-12);
      EXPECT_NEAR(mesh.v_param[i], 0.0f, 1e-6f);
    }
  }
}

TEST(TessellatorTest, ReusedMeshIsNotReallocated) {
  const std::vector<Vec3> grid_a = curvedGrid(2, 5, 3u);
  const std::vector<Vec3> grid_b = curvedGrid(2, 5, 4u);
  for (TessellationMethod method : kMethods) {
    Tessellator tessellator(LevelOfDetail{}, method);
    StripMesh mesh;
    tessellator.tessellate(grid_a, 2, 5, 0.3, mesh);
    const Vec3* positions = mesh.positions.data();
    const Vec3* normals = mesh.normals.data();
    const Vec3* tangents = mesh.tangents.data();
    const float* v_param = mesh.v_param.data();
    const float* u_param = mesh.u_param.data();
    tessellator.tessellate(grid_b, 2, 5, 0.25, mesh);
    EXPECT_EQ(mesh.positions.data(), positions);
    EXPECT_EQ(mesh.normals.data(), normals);
    EXPECT_EQ(mesh.tangents.data(), tangents);
    EXPECT_EQ(mesh.v_param.data(), v_param);
    EXPECT_EQ(mesh.u_param.data(), u_param);
    // And the second result is the second strip's, not a leftover.
    StripMesh fresh;
    Tessellator(LevelOfDetail{}, method).tessellate(grid_b, 2, 5, 0.25, fresh);
    EXPECT_EQ(maxPositionDifference(mesh, fresh), 0.0);
  }
}

TEST(TessellatorTest, LadderAndLevelOfDetailSelection) {
  EXPECT_EQ(Tessellator::ladderLevel(0).samples_across, 1);
  EXPECT_EQ(Tessellator::ladderLevel(0).samples_along, 1);
  EXPECT_EQ(Tessellator::ladderLevel(3).samples_across, 2);  // the default (2, 4)
  EXPECT_EQ(Tessellator::ladderLevel(3).samples_along, 4);
  EXPECT_EQ(Tessellator::ladderLevel(5).samples_across, 3);
  EXPECT_EQ(Tessellator::ladderLevel(5).samples_along, 6);

  const std::vector<StripShape> hairstyle(100, StripShape{2, 5});
  // Per strip: (1,1) 8, (1,2) 16, (1,3) 24, (2,4) 64, (2,5) 80 triangles.
  LevelOfDetail level = Tessellator::selectLevelOfDetail(hairstyle, 6400);
  EXPECT_EQ(level.samples_across, 2);
  EXPECT_EQ(level.samples_along, 4);
  level = Tessellator::selectLevelOfDetail(hairstyle, 6399);
  EXPECT_EQ(level.samples_across, 1);
  EXPECT_EQ(level.samples_along, 3);
  level = Tessellator::selectLevelOfDetail(hairstyle, 800);
  EXPECT_EQ(level.samples_across, 1);
  EXPECT_EQ(level.samples_along, 1);
  level = Tessellator::selectLevelOfDetail(hairstyle, 1000000000);
  EXPECT_EQ(level.samples_along, Tessellator::kMaxSelectableSamplesAlong);
  EXPECT_EQ(level.samples_across, Tessellator::kMaxSelectableSamplesAlong / 2);

  const std::vector<StripShape> mixed = {{2, 5}, {4, 8}, {3, 4}, {5, 6}};
  for (std::int64_t budget : {200, 500, 1000, 3000, 7777, 20000, 100000}) {
    const LevelOfDetail chosen = Tessellator::selectLevelOfDetail(mixed, budget);
    EXPECT_LE(Tessellator::triangleCount(mixed, chosen), budget);
    if (chosen.samples_along < Tessellator::kMaxSelectableSamplesAlong) {
      const LevelOfDetail next = Tessellator::ladderLevel(chosen.samples_along);  // ladder index = along - 1
      EXPECT_GT(Tessellator::triangleCount(mixed, next), budget);
    }
  }
  EXPECT_EQ(Tessellator::selectLevelOfDetail({}, 10).samples_along, Tessellator::kMaxSelectableSamplesAlong);
}

TEST(TessellatorTest, BadInputsThrowNamingTheValue) {
  expectInvalid([] { Tessellator t(LevelOfDetail{0, 4}); }, "samples_across must be in [1, 64], got 0");
  expectInvalid([] { Tessellator t(LevelOfDetail{2, -1}); }, "samples_along must be in [1, 64], got -1");
  Tessellator tessellator;
  expectInvalid([&] { tessellator.setLevelOfDetail(LevelOfDetail{2, 65}); }, "got 65");
  StripMesh mesh;
  const std::vector<Vec3> grid = curvedGrid(2, 5, 9u);
  expectInvalid([&] { tessellator.tessellate(grid.data(), 1, 10, 0.3, mesh); },
                "columns must be >= 2, got 1");
  expectInvalid([&] { tessellator.tessellate(grid.data(), 5, 2, 0.3, mesh); }, "rows must be >= 4, got 2");
  expectInvalid([&] { tessellator.tessellate(grid, 2, 4, 0.3, mesh); }, "10 points, columns * rows = 8");
  expectInvalid([&] { tessellator.tessellate(nullptr, 2, 5, 0.3, mesh); }, "null");
  expectInvalid([&] { tessellator.tessellate(grid, 2, 5, 0.0, mesh); },
                "hair_length must be positive and finite, got 0");
  expectInvalid([&] { tessellator.tessellate(grid, 2, 5, -0.2, mesh); }, "got -0.2");
  expectInvalid([&] { tessellator.tessellate(grid, 2, 5, std::numeric_limits<double>::quiet_NaN(), mesh); },
                "nan");
  std::vector<Vec3> bad = grid;
  bad[6].z() = std::numeric_limits<double>::infinity();
  expectInvalid([&] { tessellator.tessellate(bad, 2, 5, 0.3, mesh); }, "control point 6 (column 0, row 3)");
  // Every coordinate of the grid (both halves of the SIMD check's pairs), NaN and infinities alike; and the
  // last coordinate of a grid with an odd count of them (3 x 5 x 3 = 45: the scalar tail).
  const double non_finite[3] = {std::numeric_limits<double>::quiet_NaN(),
                                std::numeric_limits<double>::infinity(),
                                -std::numeric_limits<double>::infinity()};
  for (int k = 0; k < 30; ++k) {
    bad = grid;
    bad[static_cast<std::size_t>(k / 3)][k % 3] = non_finite[k % 3];
    expectInvalid([&] { tessellator.tessellate(bad, 2, 5, 0.3, mesh); },
                  "control point " + std::to_string(k / 3) + " (");
  }
  std::vector<Vec3> wide(15);
  for (int i = 0; i < 15; ++i) {
    wide[static_cast<std::size_t>(i)] = Vec3(0.01 * (i % 3), 0.0, -0.05 * (i / 3));
  }
  EXPECT_NO_THROW(tessellator.tessellate(wide, 3, 5, 0.3, mesh));
  wide[14].z() = std::numeric_limits<double>::quiet_NaN();
  expectInvalid([&] { tessellator.tessellate(wide, 3, 5, 0.3, mesh); }, "control point 14 (column 2, row 4)");
  // Finite extremes are finite: the largest, the smallest subnormal, negative zero.
  bad = grid;
  bad[3].x() = std::numeric_limits<double>::max();
  bad[4].y() = std::numeric_limits<double>::denorm_min();
  bad[5].z() = -0.0;
  EXPECT_NO_THROW(tessellator.tessellate(bad, 2, 5, 0.3, mesh));
  expectInvalid(
      [] {
        Tessellator::triangleCount({{2, 5}, {1, 5}}, LevelOfDetail{});
      },
      "strip 1 : columns must be >= 2, got 1");
  expectInvalid(
      [] {
        Tessellator::triangleCount(StripShape{2, 3}, LevelOfDetail{});
      },
      "rows must be >= 4, got 3");
  expectInvalid([] { Tessellator::selectLevelOfDetail({{2, 5}}, 0); }, "max_triangles must be > 0, got 0");
  expectInvalid(
      [] {
        Tessellator::selectLevelOfDetail(std::vector<StripShape>(100, StripShape{2, 5}), 799);
      },
      "max_triangles 799 is below the minimum level's 800 triangles");
  expectInvalid([] { Tessellator::ladderLevel(-1); }, "got -1");
}

/// The meshes' every bit (vertex grids, positions, frames, parameters).
bool sameMesh(const StripMesh& a, const StripMesh& b) {
  const std::size_t n = a.positions.size();
  return a.n_u == b.n_u && a.n_v == b.n_v && b.positions.size() == n && b.normals.size() == n &&
         b.tangents.size() == n && a.v_param.size() == n && b.v_param.size() == n && a.u_param.size() == n &&
         b.u_param.size() == n &&
         std::memcmp(a.positions.data(), b.positions.data(), n * sizeof(Vec3)) == 0 &&
         std::memcmp(a.normals.data(), b.normals.data(), n * sizeof(Vec3)) == 0 &&
         std::memcmp(a.tangents.data(), b.tangents.data(), n * sizeof(Vec3)) == 0 &&
         std::memcmp(a.v_param.data(), b.v_param.data(), n * sizeof(float)) == 0 &&
         std::memcmp(a.u_param.data(), b.u_param.data(), n * sizeof(float)) == 0;
}

// The meshes of one tessellate() call per strip (CachedBasis, a Tessellator of their own): what the batch
// form must give bit for bit.
std::vector<StripMesh> oneCallPerStrip(const LevelOfDetail& level, const StripInput* strips,
                                       std::size_t count) {
  Tessellator single(level, TessellationMethod::CachedBasis);
  std::vector<StripMesh> meshes(count);
  for (std::size_t i = 0; i < count; ++i) {
    single.tessellate(strips[i].control_points, strips[i].columns, strips[i].rows, strips[i].hair_length,
                      meshes[i]);
  }
  return meshes;
}

// The batch form gives one call per strip's meshes bit for bit: runs of 2-column strips of one row count
// (four to an AVX2 kernel call, one per lane) between strips of other shapes, clipped and unclipped, a
// degenerate strip among them, runs of four strips that are all clipped (the kernel stops after the last
// crossing), at levels with 2-4 vertex columns (strips in lanes) and 5 (one by one), into
// meshes that held other grids before.
TEST(TessellatorTest, BatchGivesTheMeshesOfOneCallPerStrip) {
  for (const LevelOfDetail& level : {LevelOfDetail{1, 1}, LevelOfDetail{2, 4}, LevelOfDetail{3, 5},
                                     LevelOfDetail{4, 3}, LevelOfDetail{2, 9}}) {
    Tessellator batch(level, TessellationMethod::CachedBasis);
    std::vector<std::vector<Vec3>> grids;
    std::vector<StripInput> strips;
    const int shapes[][2] = {{2, 5}, {2, 5}, {2, 5}, {2, 5}, {2, 5}, {2, 5}, {3, 5}, {2, 6},
                             {2, 6}, {2, 6}, {2, 6}, {2, 5}, {2, 6}, {2, 6}, {2, 6}, {2, 6},
                             {4, 7}, {2, 4}, {2, 4}, {2, 4}, {2, 4}, {2, 4}, {2, 4}, {2, 4}};
    for (const auto& shape : shapes) {
      grids.push_back(curvedGrid(shape[0], shape[1], static_cast<unsigned>(grids.size()) + 40u));
    }
    grids[9].assign(grids[9].size(), Vec3(0.1, 0.2, 0.3));  // every point the same: the frames' fallback
    for (std::size_t i = 0; i < grids.size(); ++i) {
      const int rows = shapes[i][1];
      const double hair_length = i % 5 == 4 ? 10.0 : 0.04 * rows + 0.01 * static_cast<double>(i % 3);
      strips.push_back({grids[i].data(), shapes[i][0], rows, hair_length});
    }
    const std::vector<StripMesh> expected = oneCallPerStrip(level, strips.data(), strips.size());
    std::vector<StripMesh> meshes(strips.size());
    for (std::size_t i = 0; i < strips.size(); ++i) {  // other grids first
      batch.tessellate(grids[(i + 7) % grids.size()], shapes[(i + 7) % grids.size()][0],
                       shapes[(i + 7) % grids.size()][1], 0.2, meshes[i]);
    }
    batch.tessellate(strips.data(), strips.size(), meshes.data());
    for (std::size_t i = 0; i < strips.size(); ++i) {
      EXPECT_TRUE(sameMesh(meshes[i], expected[i]))
          << "level " << level.samples_across << " x " << level.samples_along << ", strip " << i;
    }
    // A count that is no multiple of four, from an odd start.
    std::vector<StripMesh> part(7);
    batch.tessellate(strips.data() + 1, part.size(), part.data());
    for (std::size_t i = 0; i < part.size(); ++i) EXPECT_TRUE(sameMesh(part[i], expected[i + 1])) << i;
  }
}

// The node's hairstyle: in most columns the hair length ends in the last span, so the batch's clip (in lanes)
// runs at the last row of most columns. The meshes must be those of one call per strip, and a clipped
// column's vertices must walk exactly the strip's hair length from the file (the sum of the segments'
// lengths).
TEST(TessellatorTest, BatchGivesTheDefaultHairstylesMeshesOfOneCallPerStrip) {
  const Hairstyle hairstyle = loadHairstyle(test::repoPath("config/hairstyles/default.yaml"));
  std::vector<StripInput> strips;
  for (const Strip& strip : hairstyle.strips) {
    strips.push_back({strip.points.data(), strip.columns, strip.rows, strip.hair_length});
  }
  for (const LevelOfDetail& level : {LevelOfDetail{}, LevelOfDetail{1, 1}, LevelOfDetail{3, 6}}) {
    Tessellator batch(level, TessellationMethod::CachedBasis);
    std::vector<StripMesh> meshes(strips.size());
    batch.tessellate(strips.data(), strips.size(), meshes.data());
    const std::vector<StripMesh> expected = oneCallPerStrip(level, strips.data(), strips.size());
    int clipped_columns = 0;
    for (std::size_t i = 0; i < strips.size(); ++i) {
      EXPECT_TRUE(sameMesh(meshes[i], expected[i]))
          << "level " << level.samples_across << " x " << level.samples_along << ", strip " << i;
      const StripMesh& mesh = meshes[i];
      for (int iu = 0; iu < mesh.n_u; ++iu) {
        if (mesh.v_param[static_cast<std::size_t>((mesh.n_v - 1) * mesh.n_u + iu)] != 1.0f) continue;
        ++clipped_columns;
        double walked = 0.0;
        for (int iv = 1; iv < mesh.n_v; ++iv) {
          walked += (mesh.positions[static_cast<std::size_t>(iv * mesh.n_u + iu)] -
                     mesh.positions[static_cast<std::size_t>((iv - 1) * mesh.n_u + iu)])
                        .norm();
        }
        EXPECT_NEAR(walked, strips[i].hair_length, 1e-12) << "strip " << i << ", column " << iu;
      }
    }
    // (At the default level 203 of the 300 columns are clipped, at 1 x 1 39: the coarser polyline is
    // shorter.)
    EXPECT_GT(clipped_columns, level.samples_along == 4 ? 150 : 0)
        << "level " << level.samples_across << " x " << level.samples_along;
  }
}

// Finite control points so far apart that |dS/du x dS/dv|^2 overflows to inf - inf = NaN: every path (the
// batch's lanes and clip, one call per strip, the SSE2 and scalar frames) must take the same frame (the
// fallback), so the batch gives the bytes of one call per strip, NaN included.
TEST(TessellatorTest, FramesWithANanNormalTakeTheFallbackInEveryPath) {
  const int rows = 5;
  std::vector<Vec3> huge(2 * rows);
  std::vector<Vec3> plain(2 * rows);
  for (int r = 0; r < rows; ++r) {
    huge[static_cast<std::size_t>(2 * r)] = Vec3(0.0, 1e10 * r, 1e10 * r);
    huge[static_cast<std::size_t>(2 * r + 1)] = Vec3(0.0, 1e300, 1e300);
    plain[static_cast<std::size_t>(2 * r)] = Vec3(0.0, 0.0, -0.02 * r);
    plain[static_cast<std::size_t>(2 * r + 1)] = Vec3(0.01, 0.0, -0.02 * r);
  }
  for (const LevelOfDetail& level :
       {LevelOfDetail{1, 1}, LevelOfDetail{1, 4}, LevelOfDetail{2, 4}, LevelOfDetail{3, 4}}) {
    for (int variant = 0; variant < 2; ++variant) {  // four huge strips; one huge among plain ones
      Tessellator batch(level, TessellationMethod::CachedBasis);
      StripInput strips[4];
      for (int l = 0; l < 4; ++l) {
        const bool is_huge = variant == 0 || l == 0;
        strips[l] = {is_huge ? huge.data() : plain.data(), 2, rows, is_huge ? 3e10 : 0.05};
      }
      StripMesh meshes[4];
      batch.tessellate(strips, 4, meshes);
      const std::vector<StripMesh> expected = oneCallPerStrip(level, strips, 4);
      for (int l = 0; l < 4; ++l) {
        EXPECT_TRUE(sameMesh(meshes[l], expected[static_cast<std::size_t>(l)]))
            << "level " << level.samples_across << " x " << level.samples_along << ", variant " << variant
            << ", strip " << l;
      }
    }
  }
}

TEST(TessellatorTest, BatchChecksEveryStripBeforeChangingAnyMesh) {
  Tessellator tessellator;
  std::vector<std::vector<Vec3>> grids;
  for (unsigned i = 0; i < 8; ++i) grids.push_back(curvedGrid(2, 5, 60u + i));
  std::vector<StripInput> strips;
  for (const auto& g : grids) strips.push_back({g.data(), 2, 5, 0.3});
  std::vector<StripMesh> meshes(strips.size());
  tessellator.tessellate(strips.data(), strips.size(), meshes.data());
  const std::vector<StripMesh> before = meshes;
  auto expectUnchanged = [&] {
    for (std::size_t i = 0; i < meshes.size(); ++i) EXPECT_TRUE(sameMesh(meshes[i], before[i])) << i;
  };
  std::vector<Vec3> bad = grids[6];
  bad[7].y() = std::numeric_limits<double>::quiet_NaN();
  std::vector<StripInput> broken = strips;
  broken[6].control_points = bad.data();
  expectInvalid([&] { tessellator.tessellate(broken.data(), broken.size(), meshes.data(), 100); },
                "strip 106 : control point 7 (column 1, row 3) is not finite");
  expectUnchanged();
  broken = strips;
  broken[5].hair_length = 0.0;
  expectInvalid([&] { tessellator.tessellate(broken.data(), broken.size(), meshes.data()); },
                "strip 5 : hair_length must be positive and finite, got 0");
  broken = strips;
  broken[3].columns = 1;
  expectInvalid([&] { tessellator.tessellate(broken.data(), broken.size(), meshes.data()); },
                "strip 3 : columns must be >= 2, got 1");
  broken = strips;
  broken[7].control_points = nullptr;
  expectInvalid([&] { tessellator.tessellate(broken.data(), broken.size(), meshes.data()); },
                "strip 7 : control_points is null");
  expectUnchanged();
  expectInvalid([&] { tessellator.tessellate(nullptr, 2, meshes.data()); }, "strips is null with count 2");
  expectInvalid([&] { tessellator.tessellate(strips.data(), 2, nullptr); }, "meshes is null with count 2");
  tessellator.tessellate(nullptr, 0, nullptr);  // nothing to do
  expectUnchanged();
}

}  // namespace
}  // namespace hair_sim
