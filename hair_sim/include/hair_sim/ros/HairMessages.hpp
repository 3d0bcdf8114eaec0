#pragma once
/// The ROS messages of hair_sim, built from the core's state: one place for the node, the head
/// driver and the offline runner's bag writer.
#include <geometry_msgs/Point.h>
#include <geometry_msgs/TransformStamped.h>
#include <hair_sim_msgs/HairEvent.h>
#include <hair_sim_msgs/HairState.h>
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
/// makeHairMarkers into `array`, reusing its buffers (no allocation once they have grown).
void fillHairMarkers(const HairMeshBuilder& meshes, RenderMode mode, int strands_per_strip,
                     const std::string& frame, const ros::Time& stamp,
                     visualization_msgs::MarkerArray& array);

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
