#include "hair_sim/core/model/SimConfig.hpp"

#include <stdexcept>

#include "hair_sim/core/util/YamlReader.hpp"

namespace hair_sim {

std::string resolveRelativeTo(const std::string& file, const std::string& relative) {
  if (relative.empty() || relative.front() == '/') return relative;
  const std::size_t slash = file.find_last_of('/');
  return slash == std::string::npos ? relative : file.substr(0, slash + 1) + relative;
}

namespace {

void checkFrame(const YamlReader& y, const std::string& key, const std::string& frame) {
  if (frame.empty() || frame.find_first_of(" \t") != std::string::npos || frame.front() == '/')
    throw y.error(key, "'" + frame + "' is not a valid tf frame name (non-empty, no spaces, no leading '/')");
}

}  // namespace

SimConfig loadSimConfig(const std::string& path) {
  const YamlReader y = YamlReader::loadFile(path);
  y.requireKeys({"world_frame", "head_frame", "publish_rate", "hairstyle", "physics"});
  SimConfig c;
  c.world_frame = y.getString("world_frame", c.world_frame);
  checkFrame(y, "world_frame", c.world_frame);
  c.head_frame = y.getString("head_frame", c.head_frame);
  checkFrame(y, "head_frame", c.head_frame);
  if (c.head_frame == c.world_frame)
    throw y.error("head_frame", "must differ from world_frame '" + c.world_frame + "'");
  c.publish_rate = y.getDouble("publish_rate", 0.1, 1000.0, c.publish_rate);
  c.hairstyle_file = resolveRelativeTo(path, y.getString("hairstyle"));
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
    if (q.gravity.norm() > 1000.0) throw p.error("gravity", "magnitude above 1000 m/s^2");
  }
  if (c.publish_rate * c.physics.substep > 1.0 + 1e-9)
    throw y.error("publish_rate", formatDouble(c.publish_rate) + " Hz is faster than one substep (" +
                                      formatDouble(c.physics.substep) + " s)");
  return c;
}

}  // namespace hair_sim
