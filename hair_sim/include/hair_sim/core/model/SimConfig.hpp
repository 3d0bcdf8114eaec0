#pragma once
/// The parameter file shared by the node and the offline runner (config/hair_sim.yaml).
#include <string>

#include <vector>

#include "hair_sim/core/model/Body.hpp"
#include "hair_sim/core/model/PhysicsParameters.hpp"

namespace hair_sim {

struct SimConfig {
  std::string world_frame = "world";
  std::string head_frame = "head";
  double publish_rate = 30.0;  ///< Hz
  std::string hairstyle_file;  ///< absolute, resolved against the config file's folder
  PhysicsParameters physics;
  std::vector<Body> bodies;  ///< collision ellipsoids, each in its own frame
};

/// Loads and validates; throws std::invalid_argument naming the file, key, line and value.
SimConfig loadSimConfig(const std::string& path);

/// A tf2 frame name: non-empty, no spaces, no leading '/'.
bool isValidFrameName(const std::string& frame);

/// `relative` resolved against the folder of `file` (unchanged when already absolute).
std::string resolveRelativeTo(const std::string& file, const std::string& relative);

}  // namespace hair_sim
