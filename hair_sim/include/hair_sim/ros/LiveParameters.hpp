#pragma once
/// Live tuning of hair_sim_node through dynamic_reconfigure (cfg/HairSim.cfg): stiffness, damping, drag,
/// collision and spring constants, the spring factors, a wind scale, the render mode and the level of
/// detail. The reconfigure callback only validates and stores; the node takes the new settings between
/// two substeps (takePending), so a change never lands in the middle of a step, whatever thread the
/// callback runs on.
#include <dynamic_reconfigure/server.h>
#include <hair_sim/HairSimConfig.h>
#include <ros/ros.h>

#include <boost/thread/recursive_mutex.hpp>
#include <memory>
#include <mutex>
#include <string>

#include "hair_sim/core/geometry/HairMeshBuilder.hpp"
#include "hair_sim/core/model/PhysicsParameters.hpp"

namespace hair_sim {

/// Everything that can change while the node runs.
struct LiveSettings {
  PhysicsParameters physics;
  double wind_scale = 1.0;
  std::string render_mode = "mesh";  ///< mesh, strands or both
  HairMeshOptions mesh;
};

class LiveParameters {
 public:
  /// Starts the server on `private_nh` (services ~set_parameters, topics ~parameter_descriptions and
  /// ~parameter_updates) with `initial`: the ~ parameters of the tunable names are set to it first, so a
  /// start always begins from the config file, not from values a previous run left on the master.
  /// Throws std::invalid_argument naming the parameter when `initial` is outside a range of the cfg.
  /// `min_triangles`: the hairstyle's triangle count at the coarsest level of detail; a max_triangles
  /// below it (but 0, off) is refused.
  LiveParameters(ros::NodeHandle private_nh, const LiveSettings& initial, std::int64_t min_triangles = 0);

  /// True, with the settings, when they changed since the last call (thread-safe).
  bool takePending(LiveSettings& out);

  /// Checks a set: the physics through PhysicsParameters::validate, the render mode by name. Returns an
  /// empty string when good, else what is wrong (parameter and value).
  static std::string check(const LiveSettings& settings, std::int64_t min_triangles = 0);

 private:
  void onReconfigure(HairSimConfig& config, std::uint32_t level);
  static HairSimConfig toConfig(const LiveSettings& settings);
  static LiveSettings fromConfig(const HairSimConfig& config, const LiveSettings& base);

  std::mutex mutex_;
  LiveSettings accepted_;  ///< the last valid settings (guarded by mutex_)
  bool pending_ = false;   ///< accepted_ not yet taken by the node
  std::int64_t min_triangles_ = 0;
  boost::recursive_mutex server_mutex_;
  std::unique_ptr<dynamic_reconfigure::Server<HairSimConfig>> server_;
};

}  // namespace hair_sim
