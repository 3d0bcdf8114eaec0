/// The node's output messages (hair_sim/ros/HairMessages.hpp), without a master: hair_markers carries one
/// winding with the alpha of the former two coincident layers, hair_state float32 xyz, and a reused message
/// comes out the same as a fresh one.
#include "hair_sim/ros/HairMessages.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "TestUtil.hpp"
#include "hair_sim/core/model/HairstyleIO.hpp"
#include "hair_sim/core/model/SimConfig.hpp"

namespace hair_sim {
namespace {

struct Fixture {
  SimConfig config = loadSimConfig(test::repoPath("config/hair_sim.yaml"));
  Simulator sim{loadHairstyle(config.hairstyle_file), config.physics, config.bodies};
  HairMeshBuilder meshes{sim.hairstyle(), HairMeshOptions()};
  Fixture() { meshes.build(sim.positionsHead(), sim.stripOffsets(), sim.hairstyle().scalp); }
};

TEST(HairMessagesTest, MarkersCarryOneWindingWithTheAlphaOfTwoLayers) {
  Fixture f;
  const visualization_msgs::MarkerArray a =
      makeHairMarkers(f.meshes, RenderMode::Mesh, 6, "world", ros::Time(1.0));
  ASSERT_EQ(a.markers.size(), 1u);
  const visualization_msgs::Marker& m = a.markers[0];
  EXPECT_EQ(m.type, visualization_msgs::Marker::TRIANGLE_LIST);
  ASSERT_EQ(static_cast<std::int64_t>(m.points.size()), 3 * f.meshes.triangleCount());  // one winding
  ASSERT_EQ(m.colors.size(), m.points.size());
  // The first strip's first cell: (a, b, c) then (b, d, c), as Tessellator::appendTriangles orders them.
  const StripMesh& mesh = f.meshes.meshes()[0];
  const int cell[6] = {0, 1, mesh.n_u, 1, mesh.n_u + 1, mesh.n_u};
  for (int k = 0; k < 6; ++k) {
    const Vec3& p = mesh.positions[static_cast<std::size_t>(cell[k])];
    EXPECT_EQ(m.points[k].x, p.x());
    EXPECT_EQ(m.points[k].y, p.y());
    EXPECT_EQ(m.points[k].z, p.z());
    const Rgba& c = f.meshes.colours()[0][static_cast<std::size_t>(cell[k])];
    EXPECT_EQ(m.colors[k].r, c.r);
    EXPECT_FLOAT_EQ(m.colors[k].a, 1.f - (1.f - c.a) * (1.f - c.a));
  }
}

TEST(HairMessagesTest, ReusedMessagesEqualFreshOnes) {
  Fixture f;
  visualization_msgs::MarkerArray reused;
  fillHairMarkers(f.meshes, RenderMode::Both, 6, "world", ros::Time(1.0), reused);  // grown once
  fillHairMarkers(f.meshes, RenderMode::Mesh, 6, "world", ros::Time(2.0), reused);
  EXPECT_EQ(reused, makeHairMarkers(f.meshes, RenderMode::Mesh, 6, "world", ros::Time(2.0)));
  fillHairMarkers(f.meshes, RenderMode::Both, 6, "world", ros::Time(3.0), reused);
  EXPECT_EQ(reused, makeHairMarkers(f.meshes, RenderMode::Both, 6, "world", ros::Time(3.0)));

  std::vector<Vec3> world;
  f.sim.positionsWorld(Iso3::Identity(), world);
  hair_sim_msgs::HairState state;
  fillHairState(f.sim, world, "world", ros::Time(1.0), state);
  fillHairState(f.sim, world, "world", ros::Time(2.0), state);
  EXPECT_EQ(state, makeHairState(f.sim, world, "world", ros::Time(2.0)));
  ASSERT_EQ(state.strips.size(), f.sim.hairstyle().strips.size());
  const hair_sim_msgs::StripState& s = state.strips[1];
  ASSERT_EQ(s.xyz.size(), 3u * s.columns * s.rows);
  const Vec3& p = world[static_cast<std::size_t>(f.sim.stripOffsets()[1] + 2)];
  EXPECT_EQ(s.xyz[6], static_cast<float>(p.x()));
  EXPECT_EQ(s.xyz[7], static_cast<float>(p.y()));
  EXPECT_EQ(s.xyz[8], static_cast<float>(p.z()));
}

/// The bytes roscpp sends for a message (its serialisation, without the length prefix).
template <typename M>
std::vector<std::uint8_t> bytesOf(const M& message) {
  const ros::SerializedMessage serialized = ros::serialization::serializeMessage(message);
  return std::vector<std::uint8_t>(serialized.message_start, serialized.buf.get() + serialized.num_bytes);
}

TEST(HairMessagesTest, MarkersViewSendsTheBytesOfTheMarkerArray) {
  Fixture f;
  // A bent hairstyle (the meshes of a violent shake) and every mode, the view reused across modes.
  std::vector<Vec3> world;
  StepInputs in;
  in.body_frames.assign(f.config.bodies.size(), Iso3::Identity());
  for (int k = 0; k < 60; ++k) {
    in.head.angular_velocity = Vec3(0.0, 0.0, 12.0 * std::sin(0.3 * k));
    in.wind = Vec3(3.0, 1.0, 0.0);
    f.sim.step(in);
  }
  f.sim.positionsWorld(Iso3::Identity(), world);
  f.meshes.build(world, f.sim.stripOffsets(), f.sim.hairstyle().scalp);
  HairMarkersView view;
  for (RenderMode mode : {RenderMode::Both, RenderMode::Mesh, RenderMode::Strands, RenderMode::Both}) {
    const ros::Time stamp(1234.5678);
    const visualization_msgs::MarkerArray reference = makeHairMarkers(f.meshes, mode, 6, "odom", stamp);
    view.update(f.meshes, mode, 6, "odom", stamp);
    const std::vector<std::uint8_t> expected = bytesOf(reference);
    EXPECT_EQ(view.serializedLength(), expected.size());
    EXPECT_TRUE(bytesOf(view) == expected) << "mode " << static_cast<int>(mode);
    // What a subscriber gets back is the MarkerArray.
    const std::vector<std::uint8_t> sent = bytesOf(view);
    visualization_msgs::MarkerArray received;
    ros::serialization::IStream in_stream(const_cast<std::uint8_t*>(sent.data()),
                                          static_cast<std::uint32_t>(sent.size()));
    ros::serialization::deserialize(in_stream, received);
    EXPECT_EQ(received, reference);
  }
  EXPECT_STREQ(ros::message_traits::md5sum(view),
               ros::message_traits::md5sum<visualization_msgs::MarkerArray>());
  EXPECT_STREQ(ros::message_traits::datatype(view), "visualization_msgs/MarkerArray");
}

}  // namespace
}  // namespace hair_sim
