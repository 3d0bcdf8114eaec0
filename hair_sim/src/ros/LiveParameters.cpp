#include "hair_sim/ros/LiveParameters.hpp"

#include <stdexcept>

#include "hair_sim/core/util/YamlReader.hpp"
#include "hair_sim/ros/HairMessages.hpp"

namespace hair_sim {

namespace {

/// The server would clamp a start value outside the cfg's range without a word: refuse it instead.
void requireInRange(const std::string& name, double value, double min, double max) {
  if (!(value >= min && value <= max))
    throw std::invalid_argument("parameter ~" + name + ": " + formatDouble(value) +
                                " is outside the live-tuning range [" + formatDouble(min) + ", " +
                                formatDouble(max) + "] of cfg/HairSim.cfg");
}

}  // namespace

LiveParameters::LiveParameters(ros::NodeHandle private_nh, const LiveSettings& initial,
                               std::int64_t min_triangles)
    : accepted_(initial), min_triangles_(min_triangles) {
  const HairSimConfig start = toConfig(initial), min = HairSimConfig::__getMin__(),
                      max = HairSimConfig::__getMax__();
  requireInRange("hinge_stiffness", start.hinge_stiffness, min.hinge_stiffness, max.hinge_stiffness);
  requireInRange("hinge_damping", start.hinge_damping, min.hinge_damping, max.hinge_damping);
  requireInRange("air_drag", start.air_drag, min.air_drag, max.air_drag);
  requireInRange("collision_stiffness", start.collision_stiffness, min.collision_stiffness,
                 max.collision_stiffness);
  requireInRange("collision_damping", start.collision_damping, min.collision_damping, max.collision_damping);
  requireInRange("spring_stiffness", start.spring_stiffness, min.spring_stiffness, max.spring_stiffness);
  requireInRange("spring_proximity_factor", start.spring_proximity_factor, min.spring_proximity_factor,
                 max.spring_proximity_factor);
  requireInRange("spring_contact_fraction", start.spring_contact_fraction, min.spring_contact_fraction,
                 max.spring_contact_fraction);
  requireInRange("spring_far_factor", start.spring_far_factor, min.spring_far_factor, max.spring_far_factor);
  requireInRange("wind_scale", start.wind_scale, min.wind_scale, max.wind_scale);
  requireInRange("samples_across", start.samples_across, min.samples_across, max.samples_across);
  requireInRange("samples_along", start.samples_along, min.samples_along, max.samples_along);
  requireInRange("max_triangles", start.max_triangles, min.max_triangles, max.max_triangles);
  const std::string problem = check(initial, min_triangles_);
  if (!problem.empty()) throw std::invalid_argument(problem);
  // The server starts from the ~ parameters: make them the initial settings.
  start.__toServer__(private_nh);
  server_ = std::make_unique<dynamic_reconfigure::Server<HairSimConfig>>(server_mutex_, private_nh);
  server_->updateConfig(start);
  server_->setCallback([this](HairSimConfig& config, std::uint32_t level) { onReconfigure(config, level); });
}

bool LiveParameters::takePending(LiveSettings& out) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!pending_) return false;
  out = accepted_;
  pending_ = false;
  return true;
}

std::string LiveParameters::check(const LiveSettings& settings, std::int64_t min_triangles) {
  try {
    settings.physics.validate();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  RenderMode mode;
  if (!parseRenderMode(settings.render_mode, &mode))
    return "render_mode: '" + settings.render_mode + "' must be mesh, strands or both";
  if (!(settings.wind_scale >= 0.0))
    return "wind_scale: " + formatDouble(settings.wind_scale) + " must be >= 0";
  if (settings.mesh.max_triangles > 0 && settings.mesh.max_triangles < min_triangles)
    return "max_triangles: " + std::to_string(settings.mesh.max_triangles) +
           " is below the coarsest level's " + std::to_string(min_triangles) +
           " triangles (1 x 1) for this hairstyle: at least that, or 0 (off)";
  return "";
}

void LiveParameters::onReconfigure(HairSimConfig& config, std::uint32_t) {
  std::lock_guard<std::mutex> lock(mutex_);
  const LiveSettings wanted = fromConfig(config, accepted_);
  const std::string problem = check(wanted, min_triangles_);
  if (!problem.empty()) {
    // The server publishes what the callback leaves in `config`: the last good settings.
    ROS_WARN("hair_sim: reconfigure rejected (%s); keeping the previous values", problem.c_str());
    config = toConfig(accepted_);
    return;
  }
  const HairSimConfig before = toConfig(accepted_);
  if (before.__level__(config) == 0) return;  // nothing changed (the call setCallback makes)
  accepted_ = wanted;
  pending_ = true;
  ROS_INFO(
      "hair_sim: reconfigure: hinge k %g, gamma %g, air drag %g, collision k %g c %g, springs k_s %g "
      "band [%g, %g] (hard from %g x the near edge), wind x %g, render %s, level of detail %d x %d, max "
      "triangles %d",
      config.hinge_stiffness, config.hinge_damping, config.air_drag, config.collision_stiffness,
      config.collision_damping, config.spring_stiffness, config.spring_proximity_factor,
      config.spring_far_factor, config.spring_contact_fraction, config.wind_scale, config.render_mode.c_str(),
      config.samples_across, config.samples_along, config.max_triangles);
}

HairSimConfig LiveParameters::toConfig(const LiveSettings& s) {
  HairSimConfig c = HairSimConfig::__getDefault__();
  c.hinge_stiffness = s.physics.hinge_stiffness;
  c.hinge_damping = s.physics.hinge_damping;
  c.air_drag = s.physics.air_drag;
  c.collision_stiffness = s.physics.collision_stiffness;
  c.collision_damping = s.physics.collision_damping;
  c.spring_stiffness = s.physics.spring_stiffness;
  c.spring_proximity_factor = s.physics.spring_proximity_factor;
  c.spring_contact_fraction = s.physics.spring_contact_fraction;
  c.spring_far_factor = s.physics.spring_far_factor;
  c.wind_scale = s.wind_scale;
  c.render_mode = s.render_mode;
  c.samples_across = s.mesh.level_of_detail.samples_across;
  c.samples_along = s.mesh.level_of_detail.samples_along;
  c.max_triangles = static_cast<int>(s.mesh.max_triangles);
  return c;
}

LiveSettings LiveParameters::fromConfig(const HairSimConfig& c, const LiveSettings& base) {
  LiveSettings s = base;
  s.physics.hinge_stiffness = c.hinge_stiffness;
  s.physics.hinge_damping = c.hinge_damping;
  s.physics.air_drag = c.air_drag;
  s.physics.collision_stiffness = c.collision_stiffness;
  s.physics.collision_damping = c.collision_damping;
  s.physics.spring_stiffness = c.spring_stiffness;
  s.physics.spring_proximity_factor = c.spring_proximity_factor;
  s.physics.spring_contact_fraction = c.spring_contact_fraction;
  s.physics.spring_far_factor = c.spring_far_factor;
  s.wind_scale = c.wind_scale;
  s.render_mode = c.render_mode;
  s.mesh.level_of_detail = LevelOfDetail{c.samples_across, c.samples_along};
  s.mesh.max_triangles = c.max_triangles;
  return s;
}

}  // namespace hair_sim
