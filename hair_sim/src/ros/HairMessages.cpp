#include "hair_sim/ros/HairMessages.hpp"

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

visualization_msgs::MarkerArray makeHairMarkers(const HairMeshBuilder& meshes, RenderMode mode,
                                                int strands_per_strip, const std::string& frame,
                                                const ros::Time& stamp) {
  visualization_msgs::MarkerArray array;
  visualization_msgs::Marker base;
  base.header.stamp = stamp;
  base.header.frame_id = frame;
  base.pose.orientation.w = 1.0;
  base.scale.x = base.scale.y = base.scale.z = 1.0;
  base.color.r = base.color.g = base.color.b = base.color.a = 1.0f;
  base.action = visualization_msgs::Marker::ADD;
  if (mode != RenderMode::Strands) {
    // One merged TRIANGLE_LIST: every strip, both windings (both faces visible), per-vertex RGBA.
    visualization_msgs::Marker m = base;
    m.ns = "hair";
    m.id = 0;
    m.type = visualization_msgs::Marker::TRIANGLE_LIST;
    std::vector<std::uint32_t> indices;
    std::size_t total = 0;  // sized once: the message holds tens of thousands of vertices
    for (const StripMesh& mesh : meshes.meshes()) {
      indices.clear();
      Tessellator::appendTriangles(mesh, 0, true, indices);
      total += indices.size();
    }
    m.points.reserve(total);
    m.colors.reserve(total);
    for (std::size_t s = 0; s < meshes.meshes().size(); ++s) {
      const StripMesh& mesh = meshes.meshes()[s];
      const std::vector<Rgba>& colours = meshes.colours()[s];
      indices.clear();
      Tessellator::appendTriangles(mesh, 0, true, indices);
      for (std::uint32_t k : indices) {
        m.points.push_back(toPoint(mesh.positions[k]));
        m.colors.push_back(toColor(colours[k]));
      }
    }
    array.markers.push_back(std::move(m));
  }
  if (mode != RenderMode::Mesh) {
    visualization_msgs::Marker m = base;
    m.ns = "strands";
    m.id = 0;
    m.type = visualization_msgs::Marker::LINE_LIST;
    m.scale.x = 0.0015;  // line width (m)
    std::vector<Vec3> points;
    std::vector<Rgba> colours;
    for (std::size_t s = 0; s < meshes.meshes().size(); ++s)
      HairLook::strandLines(meshes.meshes()[s], strands_per_strip, points, &meshes.colours()[s], &colours);
    for (std::size_t k = 0; k < points.size(); ++k) {
      m.points.push_back(toPoint(points[k]));
      m.colors.push_back(toColor(colours[k]));
    }
    array.markers.push_back(std::move(m));
  }
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
