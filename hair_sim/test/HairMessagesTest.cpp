/// The node's output messages (hair_sim/ros/HairMessages.hpp), without a master: hair_markers carries one
/// winding with the alpha of the former two coincident layers, hair_state float32 xyz, and a reused message
/// comes out the same as a fresh one.
#include "hair_sim/ros/HairMessages.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

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
    view.update(f.meshes, mode, 6, "odom", stamp);
    visualization_msgs::MarkerArray reference;  // with the DELETEs of the namespaces the mode dropped
    fillHairMarkers(f.meshes, mode, 6, "odom", stamp, reference, view.deleted());
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

TEST(HairMessagesTest, SizeBoundHoldsAndFlagsMarkersNoSubscriberTakes) {
  Fixture f;
  HairMarkersView view;
  for (RenderMode mode : {RenderMode::Mesh, RenderMode::Strands, RenderMode::Both})
    for (int strands : {1, 6, 40}) {
      view.update(f.meshes, mode, strands, "world", ros::Time(1.0));
      EXPECT_LE(view.serializedLength(), hairMarkersSizeBound(f.meshes, mode, strands))
          << "mode " << static_cast<int>(mode) << ", " << strands << " strands";
    }
  // The default mesh: 6,400 triangles of 3 vertices, 40 bytes each (the README's 768 kB).
  EXPECT_EQ(hairMarkersSizeBound(f.meshes, RenderMode::Mesh, 6), 4096u + 768000u);
  // 10,000 strands per strip at the default 2 x 4 (16 segments a strand, 100 strips): 1.28 GB.
  EXPECT_EQ(hairMarkersSizeBound(f.meshes, RenderMode::Strands, 10000), 4096u + 40ull * 2 * 10000 * 16 * 100);
  EXPECT_GT(hairMarkersSizeBound(f.meshes, RenderMode::Strands, 10000), kMaxMarkersBytes);
  EXPECT_LT(hairMarkersSizeBound(f.meshes, RenderMode::Both, 6), kMaxMarkersBytes);
}

/// What rviz shows after a sequence of hair_markers: (ns, id) -> type, the DELETEs applied.
std::map<std::string, int> shownBy(const std::vector<visualization_msgs::MarkerArray>& messages) {
  std::map<std::string, int> shown;
  for (const visualization_msgs::MarkerArray& array : messages)
    for (const visualization_msgs::Marker& m : array.markers) {
      const std::string key = m.ns + "/" + std::to_string(m.id);
      if (m.action == visualization_msgs::Marker::DELETE)
        shown.erase(key);
      else if (m.action == visualization_msgs::Marker::DELETEALL)
        shown.clear();
      else
        shown[key] = m.type;
    }
  return shown;
}

TEST(HairMessagesTest, ARenderModeSwitchDeletesTheNamespaceItDrops) {
  Fixture f;
  std::vector<Vec3> world;
  f.sim.positionsWorld(Iso3::Identity(), world);
  f.meshes.build(world, f.sim.stripOffsets(), f.sim.hairstyle().scalp);
  HairMarkersView view;
  std::vector<visualization_msgs::MarkerArray> sent;
  auto publish = [&](RenderMode mode) {
    view.update(f.meshes, mode, 2, "world", ros::Time(10.0), 3);
    const std::vector<std::uint8_t> bytes = bytesOf(view);
    visualization_msgs::MarkerArray received;
    ros::serialization::IStream in(const_cast<std::uint8_t*>(bytes.data()),
                                   static_cast<std::uint32_t>(bytes.size()));
    ros::serialization::deserialize(in, received);
    sent.push_back(received);
    return received;
  };
  const auto tri = visualization_msgs::Marker::TRIANGLE_LIST, lines = visualization_msgs::Marker::LINE_LIST;
  publish(RenderMode::Both);
  EXPECT_EQ(sent.back().markers.size(), 2u);
  EXPECT_EQ(shownBy(sent), (std::map<std::string, int>{{"hair/0", tri}, {"strands/0", lines}}));
  // Both -> mesh: the strands go, in this message and the next two (three repeats), then no more.
  for (int k = 0; k < 4; ++k) {
    const visualization_msgs::MarkerArray m = publish(RenderMode::Mesh);
    EXPECT_EQ(view.deleted(), k < 3 ? unsigned{kDeleteStrands} : unsigned{kDeleteNone}) << "message " << k;
    ASSERT_EQ(m.markers.size(), k < 3 ? 2u : 1u) << "message " << k;
    if (k < 3) {
      EXPECT_EQ(m.markers[0].ns, "strands");
      EXPECT_EQ(m.markers[0].action, visualization_msgs::Marker::DELETE);
      EXPECT_EQ(m.markers[0].header.frame_id, "world");
    }
    EXPECT_EQ(shownBy(sent), (std::map<std::string, int>{{"hair/0", tri}})) << "message " << k;
  }
  // Mesh -> strands: the mesh goes.
  publish(RenderMode::Strands);
  EXPECT_EQ(view.deleted(), unsigned{kDeleteHair});
  EXPECT_EQ(shownBy(sent), (std::map<std::string, int>{{"strands/0", lines}}));
  // Strands -> both: nothing to delete (a DELETE of the mesh still due is dropped: the mesh is back).
  publish(RenderMode::Both);
  EXPECT_EQ(view.deleted(), unsigned{kDeleteNone});
  EXPECT_EQ(shownBy(sent), (std::map<std::string, int>{{"hair/0", tri}, {"strands/0", lines}}));
  // Both -> strands: the mesh goes.
  publish(RenderMode::Strands);
  EXPECT_EQ(shownBy(sent), (std::map<std::string, int>{{"strands/0", lines}}));
}

}  // namespace
}  // namespace hair_sim
