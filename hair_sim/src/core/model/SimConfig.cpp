#include "hair_sim/core/model/SimConfig.hpp"

#include <stdexcept>

#include "hair_sim/core/util/YamlReader.hpp"

namespace hair_sim {

std::string resolveRelativeTo(const std::string& file, const std::string& relative) {
  if (relative.empty() || relative.front() == '/') return relative;
  const std::size_t slash = file.find_last_of('/');
  return slash == std::string::npos ? relative : file.substr(0, slash + 1) + relative;
}

bool isValidFrameName(const std::string& frame) {
  return !frame.empty() && frame.find_first_of(" \t") == std::string::npos && frame.front() != '/';
}

namespace {

void checkFrame(const YamlReader& y, const std::string& key, const std::string& frame) {
  if (!isValidFrameName(frame))
    throw y.error(key, "'" + frame + "' is not a valid tf frame name (non-empty, no spaces, no leading '/')");
}

}  // namespace

SimConfig loadSimConfig(const std::string& path) {
  const YamlReader y = YamlReader::loadFile(path);
  y.requireKeys({"world_frame", "head_frame", "publish_rate", "hairstyle", "physics", "collision", "springs",
                 "bodies"});
  SimConfig c;
  c.world_frame = y.getString("world_frame", c.world_frame);
  checkFrame(y, "world_frame", c.world_frame);
  c.head_frame = y.getString("head_frame", c.head_frame);
  checkFrame(y, "head_frame", c.head_frame);
  if (c.head_frame == c.world_frame)
    throw y.error("head_frame", "must differ from world_frame '" + c.world_frame + "'");
  c.publish_rate = y.getDouble("publish_rate", 0.1, 1000.0, c.publish_rate);
  const std::string hairstyle = y.getString("hairstyle");
  if (hairstyle.empty()) throw y.error("hairstyle", "must name a hairstyle file, got an empty string");
  c.hairstyle_file = resolveRelativeTo(path, hairstyle);
  if (y.has("physics")) {
    const YamlReader p = y.child("physics");
    p.requireKeys({"substep", "gravity", "linear_density", "hinge_stiffness", "hinge_damping", "air_drag",
                   "max_angle_step", "max_bend", "compensate_rest_angles"});
    PhysicsParameters& q = c.physics;
    q.substep = p.getDouble("substep", 1e-5, 0.05, q.substep);
    q.gravity = p.getVec3("gravity", q.gravity);
    q.linear_density = p.getDouble("linear_density", 1e-6, 10.0, q.linear_density);
    q.hinge_stiffness = p.getDouble("hinge_stiffness", 0.0, 1e3, q.hinge_stiffness);
    q.hinge_damping = p.getDouble("hinge_damping", 0.0, 1e3, q.hinge_damping);
    q.air_drag = p.getDouble("air_drag", 0.0, 1e3, q.air_drag);
    q.max_angle_step = p.getDouble("max_angle_step", 1e-3, 1.5, q.max_angle_step);
    q.max_bend = p.getDouble("max_bend", 0.1, 3.0, q.max_bend);
    q.compensate_rest_angles = p.getBool("compensate_rest_angles", q.compensate_rest_angles);
    if (q.gravity.norm() > 1000.0)
      throw p.error("gravity", "[" + formatDouble(q.gravity.x()) + ", " + formatDouble(q.gravity.y()) + ", " +
                                   formatDouble(q.gravity.z()) + "]: magnitude " +
                                   formatDouble(q.gravity.norm()) + " m/s^2 is above 1000");
  }
  if (y.has("collision")) {
    const YamlReader p = y.child("collision");
    p.requireKeys({"stiffness", "damping"});
    c.physics.collision_stiffness = p.getDouble("stiffness", 0.0, 1e6, c.physics.collision_stiffness);
    c.physics.collision_damping = p.getDouble("damping", 0.0, 1e6, c.physics.collision_damping);
  }
  if (y.has("springs")) {
    const YamlReader p = y.child("springs");
    p.requireKeys({"within_strips", "between_strips", "stiffness", "proximity_factor", "contact_fraction",
                   "far_factor", "radius", "max_pairs"});
    PhysicsParameters& q = c.physics;
    q.springs_within_strips = p.getBool("within_strips", q.springs_within_strips);
    q.springs_between_strips = p.getBool("between_strips", q.springs_between_strips);
    q.spring_stiffness = p.getDouble("stiffness", 0.0, 1e6, q.spring_stiffness);
    q.spring_proximity_factor = p.getDouble("proximity_factor", 1e-3, 1.0, q.spring_proximity_factor);
    q.spring_contact_fraction = p.getDouble("contact_fraction", 0.01, 1.0, q.spring_contact_fraction);
    q.spring_far_factor = p.getDouble("far_factor", 1.0, 100.0, q.spring_far_factor);
    q.spring_radius = p.getDouble("radius", 0.0, 0.5, q.spring_radius);
    q.spring_max_pairs = p.getInt("max_pairs", 0, 16, q.spring_max_pairs);
  }
  if (y.has("bodies")) {
    const YamlReader list = y.child("bodies");
    list.requireSequence();
    for (std::size_t i = 0; i < list.size(); ++i) {
      const YamlReader b = list.at(i);
      b.requireKeys({"name", "frame", "center", "rpy", "radii"});
      Body body;
      body.name = b.getString("name");
      if (body.name.empty()) throw b.error("name", "must not be empty");
      for (const Body& other : c.bodies)
        if (other.name == body.name) throw b.error("name", "'" + body.name + "' is used by two bodies");
      body.frame = b.getString("frame");
      checkFrame(b, "frame", body.frame);
      const Vec3 radii = b.getVec3("radii");
      for (int k = 0; k < 3; ++k)
        if (!(radii[k] > 0.0 && radii[k] <= 10.0))
          throw b.error("radii", "radius " + formatDouble(radii[k]) + " m must be in (0, 10]");
      // Far beyond any room or map, and turns beyond 4 pi, are typos (a center of 1e300 m made the step 12 x
      // slower).
      const Vec3 center = b.getVec3Within("center", 1e5, "m"), rpy = b.getRpy("rpy");
      body.shape = Ellipsoid::fromRpy(center, rpy, radii);
      c.bodies.push_back(body);
    }
  }
  if (c.publish_rate * c.physics.substep > 1.0 + 1e-9)
    throw y.error("publish_rate", formatDouble(c.publish_rate) + " Hz is faster than one substep (" +
                                      formatDouble(c.physics.substep) + " s)");
  return c;
}

}  // namespace hair_sim
