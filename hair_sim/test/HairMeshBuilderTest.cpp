/// The mesh users see: root edge on the scalp, no vertex inside a body, level of detail from a budget.
#include "hair_sim/core/geometry/HairMeshBuilder.hpp"

#include <gtest/gtest.h>

#include "TestUtil.hpp"
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
  std::vector<Vec3> points;
  std::vector<int> offsets;
  for (const Strip& s : style.strips) {
    offsets.push_back(static_cast<int>(points.size()));
    points.insert(points.end(), s.points.begin(), s.points.end());
  }
  builder.build(points, offsets, style.scalp);
  EXPECT_LE(builder.triangleCount(), 5000);
  options.max_triangles = 10;  // below the coarsest level: a clear error
  EXPECT_NE(test::errorOf([&] { HairMeshBuilder b(style, options); }).find("10"), std::string::npos);
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
  EXPECT_LE(summary.max_mesh_penetration_m, 1e-3);
}

}  // namespace
}  // namespace hair_sim
