#pragma once
/// The ROS messages of hair_sim, built from the core's state: one place for the node, the head
/// driver and the offline runner's bag writer.
#include <geometry_msgs/Point.h>
#include <geometry_msgs/TransformStamped.h>
#include <hair_sim_msgs/HairEvent.h>
#include <hair_sim_msgs/HairState.h>
#include <ros/serialization.h>
#include <ros/time.h>
#include <visualization_msgs/MarkerArray.h>

#include <string>
#include <vector>

#include "hair_sim/core/Simulator.hpp"
#include "hair_sim/core/events/Event.hpp"
#include "hair_sim/core/geometry/HairMeshBuilder.hpp"
#include "hair_sim/core/model/Body.hpp"

namespace hair_sim {

/// What hair_markers carries: the tessellated strips, strand lines, or both.
enum class RenderMode { Mesh, Strands, Both };
/// The parameter's names: "mesh", "strands", "both". parseRenderMode is false for any other name.
const char* renderModeName(RenderMode mode);
bool parseRenderMode(const std::string& name, RenderMode* mode);

geometry_msgs::Point toPoint(const Vec3& p);

/// hair_state: every control point (world_points, positionsHead() order) as float32 x, y, z, with grid
/// size and hair length per strip.
hair_sim_msgs::HairState makeHairState(const Simulator& simulator, const std::vector<Vec3>& world_points,
                                       const std::string& frame, const ros::Time& stamp);
/// makeHairState into `state`, reusing its buffers (the node keeps one message while no one else holds it).
void fillHairState(const Simulator& simulator, const std::vector<Vec3>& world_points,
                   const std::string& frame, const ros::Time& stamp, hair_sim_msgs::HairState& state);

/// hair_markers from meshes already built in `frame`: ns "hair" one TRIANGLE_LIST of every strip,
/// one winding (rviz draws it with culling off and, with per-vertex colours, unlit: both faces show),
/// per-vertex RGBA; ns "strands" a LINE_LIST of strands_per_strip strands per strip.
visualization_msgs::MarkerArray makeHairMarkers(const HairMeshBuilder& meshes, RenderMode mode,
                                                int strands_per_strip, const std::string& frame,
                                                const ros::Time& stamp);
/// Namespaces of hair_markers that a message deletes (bits): a render mode that drops one (mesh to
/// strands: the "hair" mesh; both or strands to mesh: the "strands") sends a DELETE for it, ahead of its
/// markers, so that rviz does not keep showing the last marker of that namespace.
enum DeletedNamespaces : unsigned { kDeleteNone = 0, kDeleteHair = 1, kDeleteStrands = 2 };

/// makeHairMarkers into `array`, reusing its buffers (no allocation once they have grown); `deleted`
/// (DeletedNamespaces bits) puts a DELETE marker for each of those namespaces first.
void fillHairMarkers(const HairMeshBuilder& meshes, RenderMode mode, int strands_per_strip,
                     const std::string& frame, const ros::Time& stamp, visualization_msgs::MarkerArray& array,
                     unsigned deleted = kDeleteNone);

/// hair_markers' serialised size at most, in bytes, for meshes already built (exact for the mesh; the strands
/// drop zero-length segments): 40 bytes a point, 2 points a strand segment, 3 a triangle. In 64 bits: large
/// settings (10,000 strands per strip at 64 samples along) pass 4 GB.
std::uint64_t hairMarkersSizeBound(const HairMeshBuilder& meshes, RenderMode mode, int strands_per_strip);

/// What a ROS subscriber accepts at most: roscpp drops the connection on a message of over a gigabyte
/// ("a message of over a gigabyte was predicted in tcpros").
constexpr std::uint64_t kMaxMarkersBytes = 1000000000;

/// hair_markers written straight from the meshes into roscpp's buffer when published: the bytes of
/// fillHairMarkers' MarkerArray (HairMessagesTest compares them), in one pass, without filling a MarkerArray
/// first and serialising it after (in the node that took 11 % of its time with hair_markers subscribed).
/// Published as a visualization_msgs/MarkerArray (same type name, MD5 sum and definition), with
/// publish(const M&): roscpp serialises it within publish() (a subscriber in the same process receives a
/// deserialised MarkerArray). A view: the meshes must not change or go away until published.
class HairMarkersView {
 public:
  /// Takes the meshes, the mode and the header for the next publish(); the strand lines (Strands, Both)
  /// are computed here. Reuses its buffers. A namespace the previous update carried and this mode drops
  /// gets a DELETE marker in this message and the next `delete_repeats` - 1 ones (a subscriber's queue may
  /// drop a message), so that rviz removes it.
  void update(const HairMeshBuilder& meshes, RenderMode mode, int strands_per_strip, const std::string& frame,
              const ros::Time& stamp, int delete_repeats = 1);
  /// DeletedNamespaces bits of the message the last update() prepared.
  unsigned deleted() const {
    return (delete_mesh_left_ > 0 ? kDeleteHair : 0u) | (delete_strands_left_ > 0 ? kDeleteStrands : 0u);
  }
  /// Serialised size in bytes (without roscpp's 4-byte length prefix).
  std::uint32_t serializedLength() const;
  void write(ros::serialization::OStream& stream) const;

 private:
  const HairMeshBuilder* meshes_ = nullptr;
  bool mesh_ = false;
  bool strands_ = false;
  visualization_msgs::Marker mesh_shell_;     ///< every field but points and colors
  visualization_msgs::Marker strands_shell_;  ///< same
  std::vector<Vec3> strand_points_;
  std::vector<Rgba> strand_colours_;
  std::uint32_t mesh_vertices_ = 0;            ///< 3 per triangle
  int delete_mesh_left_ = 0;                   ///< messages that still carry a DELETE of ns "hair"
  int delete_strands_left_ = 0;                ///< same for ns "strands"
  visualization_msgs::Marker mesh_delete_;     ///< DELETE of ns "hair"
  visualization_msgs::Marker strands_delete_;  ///< DELETE of ns "strands"
};

/// collision_bodies: one SPHERE marker per body at its frame's pose (frames: world poses, the
/// bodies' order); the bodies in head_frame opaque, the others translucent.
visualization_msgs::MarkerArray makeBodyMarkers(const std::vector<Body>& bodies,
                                                const std::vector<Iso3>& frames,
                                                const std::string& head_frame, const std::string& frame,
                                                const ros::Time& stamp);

geometry_msgs::TransformStamped makeTransform(const Iso3& pose, const std::string& parent,
                                              const std::string& child, const ros::Time& stamp);

/// A HairEvent as a core Event starting at `start` (s), its vector taken as `vector` (already in the
/// world frame). False with `problem` = "<field>: <value> <rule>" when the type is unknown or a
/// value is bad.
bool eventFromMsg(const hair_sim_msgs::HairEvent& msg, const Vec3& vector, double start, Event* event,
                  std::string* problem);

}  // namespace hair_sim

namespace ros {
namespace message_traits {
// hair_markers is a visualization_msgs/MarkerArray whichever of the two types is published.
#define HAIR_SIM_AS_MARKER_ARRAY(Trait)                                                    \
  template <>                                                                              \
  struct Trait<hair_sim::HairMarkersView> {                                                \
    static const char* value() { return Trait<visualization_msgs::MarkerArray>::value(); } \
    static const char* value(const hair_sim::HairMarkersView&) { return value(); }         \
  };
HAIR_SIM_AS_MARKER_ARRAY(MD5Sum)
HAIR_SIM_AS_MARKER_ARRAY(DataType)
HAIR_SIM_AS_MARKER_ARRAY(Definition)
#undef HAIR_SIM_AS_MARKER_ARRAY
}  // namespace message_traits
namespace serialization {
template <>
struct Serializer<hair_sim::HairMarkersView> {
  static void write(OStream& stream, const hair_sim::HairMarkersView& view) { view.write(stream); }
  static std::uint32_t serializedLength(const hair_sim::HairMarkersView& view) {
    return view.serializedLength();
  }
};
}  // namespace serialization
}  // namespace ros
