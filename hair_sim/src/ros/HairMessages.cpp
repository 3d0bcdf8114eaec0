#include "hair_sim/ros/HairMessages.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace hair_sim {

namespace {

/// hair_markers' alpha: the coverage of the two coincident layers the markers used to carry (see
/// fillHairMarkers).
inline float twoLayerAlpha(float a) { return a * (2.f - a); }

/// A hair_markers marker's fields but its points and colours: ns "hair" TRIANGLE_LIST or ns "strands"
/// LINE_LIST (1.5 mm lines).
void markerShell(visualization_msgs::Marker& m, bool strands, const std::string& frame,
                 const ros::Time& stamp) {
  m.header.stamp = stamp;
  m.header.frame_id = frame;
  m.ns = strands ? "strands" : "hair";
  m.id = 0;
  m.type = strands ? visualization_msgs::Marker::LINE_LIST : visualization_msgs::Marker::TRIANGLE_LIST;
  m.action = visualization_msgs::Marker::ADD;
  m.pose = geometry_msgs::Pose();
  m.pose.orientation.w = 1.0;
  m.scale.x = strands ? 0.0015 : 1.0;  // a LINE_LIST's line width (m)
  m.scale.y = m.scale.z = 1.0;
  m.color.r = m.color.g = m.color.b = m.color.a = 1.0f;
}

/// A DELETE of hair_markers' marker in ns "hair" (or "strands"): the header, ns, id and action count.
void deleteShell(visualization_msgs::Marker& m, bool strands, const std::string& frame,
                 const ros::Time& stamp) {
  markerShell(m, strands, frame, stamp);
  m.action = visualization_msgs::Marker::DELETE;
}

/// Every strip's strand lines (LINE_LIST point pairs) with their colours, appended.
void allStrandLines(const HairMeshBuilder& meshes, int strands_per_strip, std::vector<Vec3>& points,
                    std::vector<Rgba>& colours) {
  for (std::size_t s = 0; s < meshes.meshes().size(); ++s)
    HairLook::strandLines(meshes.meshes()[s], strands_per_strip, points, &meshes.colours()[s], &colours);
}

std_msgs::ColorRGBA toColor(const Rgba& c) {
  std_msgs::ColorRGBA q;
  q.r = c.r;
  q.g = c.g;
  q.b = c.b;
  q.a = c.a;
  return q;
}

}  // namespace

const char* renderModeName(RenderMode mode) {
  return mode == RenderMode::Mesh ? "mesh" : mode == RenderMode::Strands ? "strands" : "both";
}

bool parseRenderMode(const std::string& name, RenderMode* mode) {
  for (const RenderMode m : {RenderMode::Mesh, RenderMode::Strands, RenderMode::Both})
    if (name == renderModeName(m)) {
      *mode = m;
      return true;
    }
  return false;
}

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
                     const std::string& frame, const ros::Time& stamp, visualization_msgs::MarkerArray& array,
                     unsigned deleted) {
  const bool delete_mesh = (deleted & kDeleteHair) != 0 && mode == RenderMode::Strands;
  const bool delete_strands = (deleted & kDeleteStrands) != 0 && mode == RenderMode::Mesh;
  const std::size_t count =
      (mode == RenderMode::Both ? 2 : 1) + (delete_mesh ? 1 : 0) + (delete_strands ? 1 : 0);
  array.markers.resize(count);
  std::size_t next = 0;
  if (delete_mesh) deleteShell(array.markers[next++], false, frame, stamp);
  if (delete_strands) deleteShell(array.markers[next++], true, frame, stamp);
  if (mode != RenderMode::Strands) {
    // One merged TRIANGLE_LIST: every strip, one winding, per-vertex RGBA. rviz 1.14's TriangleListMarker
    // draws it with culling off and, given per-vertex colours, unlit (the normals it derives from the
    // winding go unused): one winding shows both faces. The markers used to carry both windings, and
    // translucent vertices (alpha < 1 makes rviz blend the whole list without depth writes) were then
    // blended twice, one copy right after the other: alpha a drawn twice covers 1 - (1 - a)^2 = a (2 - a).
    // One winding with that alpha looks the same (exactly at the vertices; between them rviz interpolates
    // alpha linearly, which differs by at most (da)^2 / 4 along an edge whose ends differ by da).
    visualization_msgs::Marker& m = array.markers[next++];
    markerShell(m, false, frame, stamp);
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
        colour->a = twoLayerAlpha(c.a);
        ++colour;
      }
    }
  }
  if (mode != RenderMode::Mesh) {
    visualization_msgs::Marker& m = array.markers[next++];
    markerShell(m, true, frame, stamp);
    std::vector<Vec3> points;
    std::vector<Rgba> colours;
    allStrandLines(meshes, strands_per_strip, points, colours);
    m.points.resize(points.size());
    m.colors.resize(points.size());
    for (std::size_t k = 0; k < points.size(); ++k) {
      m.points[k] = toPoint(points[k]);
      m.colors[k] = toColor(colours[k]);
    }
  }
}

std::uint64_t hairMarkersSizeBound(const HairMeshBuilder& meshes, RenderMode mode, int strands_per_strip) {
  std::uint64_t points = 0;
  for (const StripMesh& mesh : meshes.meshes()) {
    if (mode != RenderMode::Strands) points += 3 * static_cast<std::uint64_t>(mesh.triangleCount());
    if (mode != RenderMode::Mesh && mesh.n_v > 1)
      points += 2 * static_cast<std::uint64_t>(std::max(strands_per_strip, 0)) * (mesh.n_v - 1);
  }
  return 4096 + (24 + 16) * points;  // (the markers' other fields: a few hundred bytes)
}

void HairMarkersView::update(const HairMeshBuilder& meshes, RenderMode mode, int strands_per_strip,
                             const std::string& frame, const ros::Time& stamp, int delete_repeats) {
  meshes_ = &meshes;
  const bool mesh = mode != RenderMode::Strands, strands = mode != RenderMode::Mesh;
  // mesh_ and strands_ still say what the previous message carried.
  delete_mesh_left_ = mesh ? 0 : mesh_ ? std::max(1, delete_repeats) : std::max(0, delete_mesh_left_ - 1);
  delete_strands_left_ = strands    ? 0
                         : strands_ ? std::max(1, delete_repeats)
                                    : std::max(0, delete_strands_left_ - 1);
  if (delete_mesh_left_ > 0) deleteShell(mesh_delete_, false, frame, stamp);
  if (delete_strands_left_ > 0) deleteShell(strands_delete_, true, frame, stamp);
  mesh_ = mesh;
  strands_ = strands;
  mesh_vertices_ = 0;
  if (mesh_) {
    markerShell(mesh_shell_, false, frame, stamp);
    for (const StripMesh& mesh : meshes.meshes())
      mesh_vertices_ += 3 * static_cast<std::uint32_t>(mesh.triangleCount());
  }
  strand_points_.clear();
  strand_colours_.clear();
  if (strands_) {
    markerShell(strands_shell_, true, frame, stamp);
    allStrandLines(meshes, strands_per_strip, strand_points_, strand_colours_);
  }
}

std::uint32_t HairMarkersView::serializedLength() const {
  namespace ser = ros::serialization;
  // A shell serialises its empty points and colours as two lengths; each point is 3 float64, each colour
  // 4 float32.
  std::uint32_t length = 4;  // the markers' count
  if (delete_mesh_left_ > 0) length += ser::serializationLength(mesh_delete_);
  if (delete_strands_left_ > 0) length += ser::serializationLength(strands_delete_);
  if (mesh_) length += ser::serializationLength(mesh_shell_) + (24 + 16) * mesh_vertices_;
  if (strands_) {
    length += ser::serializationLength(strands_shell_) +
              (24 + 16) * static_cast<std::uint32_t>(strand_points_.size());
  }
  return length;
}

namespace {

static_assert(sizeof(Vec3) == 24 && sizeof(Rgba) == 16,
              "Vec3 is three float64 and Rgba four float32, packed");

/// A marker as visualization_msgs::Marker's serializer writes it (fields in the order of its allInOne),
/// with `count` points and colours left for `fill(points, colours)` to write in place: 3 float64 and
/// 4 float32 each (little endian, as ROS serialises them on this host).
template <typename Fill>
void writeMarker(ros::serialization::OStream& stream, const visualization_msgs::Marker& shell,
                 std::uint32_t count, Fill fill) {
  stream.next(shell.header);
  stream.next(shell.ns);
  stream.next(shell.id);
  stream.next(shell.type);
  stream.next(shell.action);
  stream.next(shell.pose);
  stream.next(shell.scale);
  stream.next(shell.color);
  stream.next(shell.lifetime);
  stream.next(shell.frame_locked);
  stream.next(count);
  std::uint8_t* points = stream.advance(24 * count);
  stream.next(count);
  std::uint8_t* colours = stream.advance(16 * count);
  fill(points, colours);
  stream.next(shell.text);
  stream.next(shell.mesh_resource);
  stream.next(shell.mesh_use_embedded_materials);
}

/// One vertex: position, and colour with `alpha`.
inline void writeVertex(const Vec3& p, const Rgba& c, float alpha, std::uint8_t*& points,
                        std::uint8_t*& colours) {
  std::memcpy(points, p.data(), 24);
  points += 24;
  const float rgba[4] = {c.r, c.g, c.b, alpha};
  std::memcpy(colours, rgba, 16);
  colours += 16;
}

}  // namespace

void HairMarkersView::write(ros::serialization::OStream& stream) const {
  stream.next(static_cast<std::uint32_t>((delete_mesh_left_ > 0 ? 1 : 0) +
                                         (delete_strands_left_ > 0 ? 1 : 0) + (mesh_ ? 1 : 0) +
                                         (strands_ ? 1 : 0)));
  if (delete_mesh_left_ > 0) stream.next(mesh_delete_);
  if (delete_strands_left_ > 0) stream.next(strands_delete_);
  if (mesh_) {
    writeMarker(stream, mesh_shell_, mesh_vertices_, [this](std::uint8_t* points, std::uint8_t* colours) {
      std::vector<std::uint32_t> indices;  // one strip's triangles, built again only for a new grid size
      int n_u = -1, n_v = -1;
      for (std::size_t s = 0; s < meshes_->meshes().size(); ++s) {
        const StripMesh& mesh = meshes_->meshes()[s];
        if (mesh.n_u != n_u || mesh.n_v != n_v) {
          indices.clear();
          Tessellator::appendTriangles(mesh, 0, false, indices);
          n_u = mesh.n_u;
          n_v = mesh.n_v;
        }
        const Vec3* positions = mesh.positions.data();
        const Rgba* colours_in = meshes_->colours()[s].data();
        for (std::uint32_t k : indices)
          writeVertex(positions[k], colours_in[k], twoLayerAlpha(colours_in[k].a), points, colours);
      }
    });
  }
  if (strands_) {
    writeMarker(stream, strands_shell_, static_cast<std::uint32_t>(strand_points_.size()),
                [this](std::uint8_t* points, std::uint8_t* colours) {
                  for (std::size_t k = 0; k < strand_points_.size(); ++k)
                    writeVertex(strand_points_[k], strand_colours_[k], strand_colours_[k].a, points, colours);
                });
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
