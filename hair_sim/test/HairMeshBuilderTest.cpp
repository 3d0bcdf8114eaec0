/// The mesh users see: root edge on the scalp, no vertex inside a body, level of detail from a budget.
#include "hair_sim/core/geometry/HairMeshBuilder.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

#include "TestUtil.hpp"
#include "hair_sim/core/model/HairstyleGenerator.hpp"
#include "hair_sim/core/model/HairstyleIO.hpp"
#include "hair_sim/core/model/SimConfig.hpp"
#include "hair_sim/tools/OfflineRunner.hpp"

namespace hair_sim {
namespace {

TEST(HairMeshBuilderTest, RootEdgeLiesOnTheScalpAndCountsMatchTheFormula) {
  const SimConfig config = loadSimConfig(test::repoPath("config/hair_sim.yaml"));
  const Hairstyle style = loadHairstyle(config.hairstyle_file);
  Simulator sim(style, config.physics, config.bodies);
  HairMeshOptions options;
  options.level_of_detail = LevelOfDetail{3, 5};
  HairMeshBuilder builder(sim.hairstyle(), options);
  builder.build(sim.positionsHead(), sim.stripOffsets(), sim.hairstyle().scalp);
  std::int64_t triangles = 0;
  for (std::size_t s = 0; s < style.strips.size(); ++s) {
    const StripMesh& m = builder.meshes()[s];
    const Strip& st = style.strips[s];
    EXPECT_EQ(m.n_u, (st.columns - 1) * 3 + 1);
    EXPECT_EQ(m.n_v, (st.rows - 1) * 5 + 1);
    triangles += 2 * (m.n_u - 1) * (m.n_v - 1);
    for (int iu = 0; iu < m.n_u; ++iu) {
      const Vec3& p = m.positions[static_cast<std::size_t>(m.index(iu, 0))];
      EXPECT_LT(std::abs(style.scalp.closestPoint(p).signed_distance), 1e-6) << "strip " << s;
    }
    ASSERT_EQ(builder.colours()[s].size(), m.positions.size());
  }
  EXPECT_EQ(builder.triangleCount(), triangles);
}

TEST(HairMeshBuilderTest, EveryColumnOfTheDefaultHairstyleIsAsLongAsItsHair) {
  // The shipped hairstyle at rest, default level of detail: each tessellated column's polyline
  // length equals the strip's hair length within 1 %.
  const SimConfig config = loadSimConfig(test::repoPath("config/hair_sim.yaml"));
  const Hairstyle style = loadHairstyle(config.hairstyle_file);
  Tessellator tessellator;
  StripMesh m;
  for (std::size_t s = 0; s < style.strips.size(); ++s) {
    const Strip& st = style.strips[s];
    tessellator.tessellate(st.points, st.columns, st.rows, st.hair_length, m);
    for (int iu = 0; iu < m.n_u; ++iu) {
      double length = 0.0;
      for (int iv = 1; iv < m.n_v; ++iv)
        length += (m.positions[static_cast<std::size_t>(m.index(iu, iv))] -
                   m.positions[static_cast<std::size_t>(m.index(iu, iv - 1))])
                      .norm();
      EXPECT_NEAR(length, st.hair_length, 0.01 * st.hair_length) << "strip " << s << " column " << iu;
    }
  }
}

TEST(HairMeshBuilderTest, TriangleBudgetChoosesTheLevel) {
  const SimConfig config = loadSimConfig(test::repoPath("config/hair_sim.yaml"));
  const Hairstyle style = loadHairstyle(config.hairstyle_file);
  HairMeshOptions options;
  options.max_triangles = 5000;
  HairMeshBuilder builder(style, options);
  std::vector<int> offsets;
  const std::vector<Vec3> points = test::styledPoints(style, &offsets);
  builder.build(points, offsets, style.scalp);
  // 100 strips of 2 x 5: 8 samples_across samples_along triangles each, so the ladder's levels (1, 1), (1,
  // 2), (1, 3), (2, 4) give 800, 1600, 2400, 6400: the finest within 5000 is (1, 3).
  ASSERT_EQ(style.strips.size(), 100u);
  EXPECT_EQ(builder.triangleCount(), 2400);
  options.max_triangles = 10;  // below the coarsest level: a clear error
  EXPECT_NE(test::errorOf([&] {
              HairMeshBuilder b(style, options);
            }).find("max_triangles 10 is below the minimum level's 800 triangles"),
            std::string::npos);
}

TEST(HairMeshBuilderTest, ViolentShakeLeavesNoMeshVertexInsideABody) {
  const SimConfig config = loadSimConfig(test::repoPath("config/hair_sim.yaml"));
  Scenario scenario = Scenario::load(test::repoPath("config/scenarios/violent_shake.yaml"));
  scenario.duration = 4.0;
  OfflineRunner runner(config, loadHairstyle(config.hairstyle_file), scenario);
  RunOptions options;
  options.build_meshes = true;
  const RunSummary summary = runner.run(nullptr, options);
  EXPECT_GT(summary.mesh_vertices_projected, 0) << "the shake must push the spline surface onto the bodies";
  EXPECT_EQ(summary.max_mesh_penetration_m, 0.0);  // every vertex is put 1 um outside
}

/// Every output of a build: meshes (positions, frames, parameters) and colours, bytes compared.
bool sameBuild(const HairMeshBuilder& a, const HairMeshBuilder& b) {
  if (a.meshes().size() != b.meshes().size() || a.projectedVertices() != b.projectedVertices()) return false;
  auto same = [](const auto& x, const auto& y) {
    return x.size() == y.size() && std::memcmp(x.data(), y.data(), x.size() * sizeof(x[0])) == 0;
  };
  for (std::size_t s = 0; s < a.meshes().size(); ++s) {
    const StripMesh& m = a.meshes()[s];
    const StripMesh& n = b.meshes()[s];
    if (m.n_u != n.n_u || m.n_v != n.n_v || !same(m.positions, n.positions) || !same(m.normals, n.normals) ||
        !same(m.tangents, n.tangents) || !same(m.v_param, n.v_param) || !same(m.u_param, n.u_param) ||
        !same(a.colours()[s], b.colours()[s]))
      return false;
  }
  return true;
}

TEST(HairMeshBuilderTest, HelperThreadsBuildTheSameMeshes) {
  const SimConfig config = loadSimConfig(test::repoPath("config/hair_sim.yaml"));
  GeneratorOptions generated;
  generated.strips = 300;  // about 19 blocks of 16 strips
  const Hairstyle style = generateHairstyle(config, Iso3::Identity(), generated);
  ASSERT_GE(style.strips.size(), static_cast<std::size_t>(HairMeshBuilder::kMinStripsForHelpers));
  Simulator sim(style, config.physics, config.bodies);
  StepInputs in;
  in.body_frames.assign(config.bodies.size(), Iso3::Identity());
  in.wind = Vec3(6.0, -4.0, 2.0);
  for (int k = 0; k < 120; ++k) sim.step(in);
  // A body just outside the scalp: the surface between the control points dips into it, so vertices are
  // moved out of it on every thread.
  const Ellipsoid& scalp = sim.hairstyle().scalp;
  const std::vector<Ellipsoid> bodies{Ellipsoid(scalp.center(), scalp.rotation(), scalp.radii() * 1.06)};
  HairMeshBuilder one(sim.hairstyle(), HairMeshOptions());
  one.build(sim.positionsHead(), sim.stripOffsets(), scalp, bodies);
  EXPECT_GT(one.projectedVertices(), 100);
  EXPECT_EQ(one.threads(), 1);
  for (int threads : {2, 3, 1}) {
    HairMeshBuilder many(sim.hairstyle(), HairMeshOptions());
    many.setThreads(threads);
    EXPECT_EQ(many.threads(), threads);
    for (int repeat = 0; repeat < 3; ++repeat) {  // reused blocks and tessellators
      many.build(sim.positionsHead(), sim.stripOffsets(), scalp, bodies);
      EXPECT_TRUE(sameBuild(one, many)) << threads << " threads, build " << repeat;
    }
  }
  HairMeshBuilder builder(sim.hairstyle(), HairMeshOptions());
  for (int bad : {0, -1, 65}) {
    try {
      builder.setThreads(bad);
      ADD_FAILURE() << "setThreads(" << bad << ") accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("got " + std::to_string(bad)), std::string::npos) << e.what();
    }
  }
  // A strip that cannot be tessellated (a non-finite control point in block 10) throws on the calling
  // thread, naming the point, with helpers as without.
  std::vector<Vec3> broken = sim.positionsHead();
  broken[static_cast<std::size_t>(sim.stripOffsets()[170] + 3)].x() = std::nan("");
  for (int threads : {1, 2}) {
    builder.setThreads(threads);
    try {
      builder.build(broken, sim.stripOffsets(), scalp, bodies);
      ADD_FAILURE() << "a NaN control point was tessellated with " << threads << " threads";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("control point 3"), std::string::npos) << e.what();
    }
  }
}

TEST(HairMeshBuilderTest, BuildRejectsBadStripOffsetsAndBuildsAfterwards) {
  const SimConfig config = loadSimConfig(test::repoPath("config/hair_sim.yaml"));
  const Hairstyle style = loadHairstyle(config.hairstyle_file);
  ASSERT_EQ(style.strips.size(), 100u);
  std::vector<int> offsets;
  const std::vector<Vec3> points = test::styledPoints(style, &offsets);
  ASSERT_EQ(points.size(), 1000u);  // 100 strips of 2 x 5 control points
  const std::vector<Ellipsoid> bodies{
      Ellipsoid(style.scalp.center(), style.scalp.rotation(), style.scalp.radii() * 1.06)};
  HairMeshOptions options;
  options.level_of_detail = LevelOfDetail{3, 5};
  HairMeshBuilder builder(style, options);
  builder.build(points, offsets, style.scalp, bodies);
  // Each strip of 2 x 5 control points: (1 x 3 + 1) x (4 x 5 + 1) vertices.
  ASSERT_EQ(builder.vertexCount(), 100 * 4 * 21);
  ASSERT_GT(builder.projectedVertices(), 0);  // the surface dips into the body: projections to compare
  const int projected = builder.projectedVertices();
  auto rejects = [&](const std::vector<Vec3>& p, const std::vector<int>& o, const std::string& text) {
    test::expectInvalid([&] { builder.build(p, o, style.scalp, bodies); }, text);
  };
  // A wrong number of offsets: the counts of both.
  std::vector<int> bad(offsets.begin(), offsets.end() - 1);
  rejects(points, bad, "99 strip offsets for 100 strips");
  bad = offsets;
  bad.push_back(1000);
  rejects(points, bad, "101 strip offsets for 100 strips");
  rejects(points, {}, "0 strip offsets for 100 strips");
  // Offsets past the points (cut short, or an offset too far or negative): the strip.
  const std::vector<Vec3> short_points(points.begin(), points.end() - 1);
  rejects(short_points, offsets,
          "too few points for strip 99: its 10 points from offset 990 need 1000, 999 given");
  bad = offsets;
  bad[40] = 995;  // strip 40's 10 points would end at 1005
  rejects(points, bad, "too few points for strip 40: its 10 points from offset 995 need 1005, 1000 given");
  bad[40] = offsets[40];
  bad[7] = -1;
  rejects(points, bad, "strip 7: offset -1 is negative");
  // The failed builds left the meshes alone, and a good build gives what a fresh builder gives.
  EXPECT_EQ(builder.vertexCount(), 100 * 4 * 21);
  EXPECT_EQ(builder.projectedVertices(), projected);  // the count that goes with them
  builder.build(points, offsets, style.scalp, bodies);
  EXPECT_EQ(builder.vertexCount(), 100 * 4 * 21);
  HairMeshBuilder fresh(style, options);
  fresh.build(points, offsets, style.scalp, bodies);
  EXPECT_TRUE(sameBuild(builder, fresh));
}

}  // namespace
}  // namespace hair_sim
