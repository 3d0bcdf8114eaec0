#include "hair_sim/ros/HairMessages.hpp"

#include <algorithm>
#include <cmath>

namespace hair_sim {

namespace {

std_msgs::ColorRGBA toColor(const Rgba& c) {
  std_msgs::ColorRGBA q;
  q.r = c.r;
  q.g = c.g;
  q.b = c.b;
  q.a = c.a;
  return q;
}

}  // namespace

geometry_msgs::Point toPoint(const Vec3& p) {
  geometry_msgs::Point q;
  q.x = p.x();
  q.y = p.y();
  q.z = p.z();
  return q;
}

void fillHairState(const Simulator& simulator, const std::vector<Vec3>& world_points,
                   const std::string& frame, const ros::Time& stamp, hair_sim_msgs::HairState& state) {
  const std::vector<int>& offsets = simulator.stripOffsets();
  const auto& strips = simulator.hairstyle().strips;
  state.header.stamp = stamp;
  state.header.frame_id = frame;
  state.step = static_cast<std::uint64_t>(simulator.stepCount());
  state.strips.resize(strips.size());
  for (std::size_t s = 0; s < strips.size(); ++s) {
    hair_sim_msgs::StripState& out = state.strips[s];
    out.columns = static_cast<std::uint32_t>(strips[s].columns);
    out.rows = static_cast<std::uint32_t>(strips[s].rows);
    out.hair_length = strips[s].hair_length;
    out.color = toColor(strips[s].color);
    const std::size_t n = static_cast<std::size_t>(strips[s].pointCount());
    out.xyz.resize(3 * n);
    const Vec3* in = world_points.data() + offsets[s];
    float* xyz = out.xyz.data();
    for (std::size_t p = 0; p < n; ++p) {
      xyz[3 * p] = static_cast<float>(in[p].x());
      xyz[3 * p + 1] = static_cast<float>(in[p].y());
      xyz[3 * p + 2] = static_cast<float>(in[p].z());
    }
  }
}

hair_sim_msgs::HairState makeHairState(const Simulator& simulator, const std::vector<Vec3>& world_points,
                                       const std::string& frame, const ros::Time& stamp) {
  hair_sim_msgs::HairState state;
  fillHairState(simulator, world_points, frame, stamp, state);
  return state;
}

void fillHairMarkers(const HairMeshBuilder& meshes, RenderMode mode, int strands_per_strip,
                     const std::string& frame, const ros::Time& stamp,
                     visualization_msgs::MarkerArray& array) {
  const std::size_t count = mode == RenderMode::Both ? 2 : 1;
  array.markers.resize(count);
  for (visualization_msgs::Marker& m : array.markers) {
    m.header.stamp = stamp;
    m.header.frame_id = frame;
    m.pose = geometry_msgs::Pose();
    m.pose.orientation.w = 1.0;
    m.scale.x = m.scale.y = m.scale.z = 1.0;
    m.color.r = m.color.g = m.color.b = m.color.a = 1.0f;
    m.action = visualization_msgs::Marker::ADD;
    m.id = 0;
  }
  std::size_t next = 0;
  if (mode != RenderMode::Strands) {
    // One merged TRIANGLE_LIST: every strip, one winding, per-vertex RGBA. rviz 1.14's TriangleListMarker
    // draws it with culling off and, given per-vertex colours, unlit (the normals it derives from the
    // winding go unused): one winding shows both faces. The markers used to carry both windings, and
    // translucent vertices (alpha < 1 makes rviz blend the whole list without depth writes) were then
    // blended twice, one copy right after the other: alpha a drawn twice covers 1 - (1 - a)^2 = a (2 - a).
    // One winding with that alpha looks the same (exactly at the vertices; between them rviz interpolates
    // alpha linearly, which differs by at most (da)^2 / 4 along an edge whose ends differ by da).
    visualization_msgs::Marker& m = array.markers[next++];
    m.ns = "hair";
    m.type = visualization_msgs::Marker::TRIANGLE_LIST;
    std::size_t total = 0;
    for (const StripMesh& mesh : meshes.meshes()) total += 3 * static_cast<std::size_t>(mesh.triangleCount());
    // Resized in place: a reused message keeps its buffers (no allocation, no page faults).
    m.points.resize(total);
    m.colors.resize(total);
    geometry_msgs::Point* point = m.points.data();
    std_msgs::ColorRGBA* colour = m.colors.data();
    std::vector<std::uint32_t> indices;  // one strip's triangles (one winding)
    for (std::size_t s = 0; s < meshes.meshes().size(); ++s) {
      const StripMesh& mesh = meshes.meshes()[s];
      const Vec3* positions = mesh.positions.data();
      const Rgba* colours = meshes.colours()[s].data();
      indices.clear();
      Tessellator::appendTriangles(mesh, 0, false, indices);
      for (std::uint32_t k : indices) {
        const Vec3& p = positions[k];
        point->x = p.x();
        point->y = p.y();
        point->z = p.z();
        ++point;
        const Rgba& c = colours[k];
        colour->r = c.r;
        colour->g = c.g;
        colour->b = c.b;
        colour->a = c.a * (2.f - c.a);  // the coverage of the former two coincident layers (above)
        ++colour;
      }
    }
  }
  if (mode != RenderMode::Mesh) {
    visualization_msgs::Marker& m = array.markers[next++];
    m.ns = "strands";
    m.type = visualization_msgs::Marker::LINE_LIST;
    m.scale.x = 0.0015;  // line width (m)
    std::vector<Vec3> points;
    std::vector<Rgba> colours;
    for (std::size_t s = 0; s < meshes.meshes().size(); ++s)
      HairLook::strandLines(meshes.meshes()[s], strands_per_strip, points, &meshes.colours()[s], &colours);
    m.points.resize(points.size());
    m.colors.resize(points.size());
    for (std::size_t k = 0; k < points.size(); ++k) {
      m.points[k] = toPoint(points[k]);
      m.colors[k] = toColor(colours[k]);
    }
  }
}

visualization_msgs::MarkerArray makeHairMarkers(const HairMeshBuilder& meshes, RenderMode mode,
                                                int strands_per_strip, const std::string& frame,
                                                const ros::Time& stamp) {
  visualization_msgs::MarkerArray array;
  fillHairMarkers(meshes, mode, strands_per_strip, frame, stamp, array);
  return array;
}

visualization_msgs::MarkerArray makeBodyMarkers(const std::vector<Body>& bodies,
                                                const std::vector<Iso3>& frames,
                                                const std::string& head_frame, const std::string& frame,
                                                const ros::Time& stamp) {
  visualization_msgs::MarkerArray array;
  for (std::size_t b = 0; b < bodies.size() && b < frames.size(); ++b) {
    const Body& body = bodies[b];
    const Ellipsoid e = body.shape.transformed(frames[b]);
    visualization_msgs::Marker m;
    m.header.stamp = stamp;
    m.header.frame_id = frame;
    m.ns = "bodies";
    m.id = static_cast<int>(b);
    m.type = visualization_msgs::Marker::SPHERE;
    m.action = visualization_msgs::Marker::ADD;
    m.pose.position = toPoint(e.center());
    const Eigen::Quaterniond q(e.rotation());
    m.pose.orientation.x = q.x();
    m.pose.orientation.y = q.y();
    m.pose.orientation.z = q.z();
    m.pose.orientation.w = q.w();
    m.scale.x = 2.0 * e.radii().x();
    m.scale.y = 2.0 * e.radii().y();
    m.scale.z = 2.0 * e.radii().z();
    // The head opaque (the hair sits on a visible head), the rest of the body translucent.
    m.color.r = 0.85f;
    m.color.g = 0.68f;
    m.color.b = 0.56f;
    m.color.a = body.frame == head_frame ? 1.0f : 0.45f;
    array.markers.push_back(m);
  }
  return array;
}

geometry_msgs::TransformStamped makeTransform(const Iso3& pose, const std::string& parent,
                                              const std::string& child, const ros::Time& stamp) {
  geometry_msgs::TransformStamped t;
  t.header.stamp = stamp;
  t.header.frame_id = parent;
  t.child_frame_id = child;
  t.transform.translation.x = pose.translation().x();
  t.transform.translation.y = pose.translation().y();
  t.transform.translation.z = pose.translation().z();
  const Eigen::Quaterniond q(pose.linear());
  t.transform.rotation.x = q.x();
  t.transform.rotation.y = q.y();
  t.transform.rotation.z = q.z();
  t.transform.rotation.w = q.w();
  return t;
}

bool eventFromMsg(const hair_sim_msgs::HairEvent& msg, const Vec3& vector, double start, Event* event,
                  std::string* problem) {
  Event e;
  if (!parseEventType(msg.type, &e.type)) {
    *problem = "type: '" + msg.type + "' is not one of " + eventTypeNames();
    return false;
  }
  e.start = start;
  e.duration = msg.duration;
  e.ease = msg.ease;
  e.vector = vector;
  e.peak = msg.peak;
  e.period = msg.period;
  e.jitter = msg.jitter;
  e.intensity = msg.intensity;
  e.length_scale = msg.length_scale;
  e.time_scale = msg.time_scale;
  e.amplitude = msg.amplitude;
  e.frequency = msg.frequency;
  e.seed = msg.seed;
  std::string field, message;
  if (e.findProblem(&field, &message)) {
    *problem = field + ": " + message;
    return false;
  }
  *event = e;
  return true;
}

}  // namespace hair_sim
