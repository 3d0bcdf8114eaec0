#pragma once
/// Runs the core without ROS: a config, a hairstyle and a scenario in, control points per output
/// frame out. hair_sim_offline is a thin command-line front end to this.
#include <csignal>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "hair_sim/core/Simulator.hpp"
#include "hair_sim/core/geometry/HairMeshBuilder.hpp"
#include "hair_sim/core/model/SimConfig.hpp"
#include "hair_sim/tools/Scenario.hpp"

namespace hair_sim {

struct RunSummary {
  long steps = 0;
  int control_points = 0;
  int strips = 0;
  int output_frames = 0;
  double sim_seconds = 0.0;
  double wall_seconds = 0.0;
  double ns_per_control_point_update = 0.0;
  double max_segment_rate = 0.0;   ///< rad/s, relative to the head
  double max_penetration_m = 0.0;  ///< deepest control point inside an inflated body over the run
  double min_strip_gap_m = 0.0;    ///< smallest distance between paired points of different strips
  double max_width_ratio = 0.0;    ///< largest distance / rest length of a within-strip spring pair
  long collisions = 0;             ///< segments turned out of a body, summed over the run
  double max_mesh_penetration_m =
      0.0;                           ///< deepest mesh vertex inside a body (no margin), when meshes are built
  long mesh_vertices = 0;            ///< per frame, when meshes are built
  long mesh_vertices_projected = 0;  ///< mesh vertices moved out of a body, summed over the frames
  long mesh_triangles = 0;           ///< per frame (single-sided), when meshes are built
  bool all_finite = true;
  long teleports = 0;  ///< substeps where the head jumped beyond RunOptions' teleport limits

  std::string toJson() const;
};

/// One output frame: time and every control point in the world frame.
struct OutputFrame {
  double t = 0.0;
  Iso3 head_pose = Iso3::Identity();
  const std::vector<Vec3>* points_world = nullptr;
  const Simulator* simulator = nullptr;
  /// Tessellated strips in the world frame (only when RunOptions::build_meshes).
  const HairMeshBuilder* meshes = nullptr;
};

struct RunOptions {
  bool build_meshes = false;  ///< tessellate every output frame (for PLY output and mesh checks)
  HairMeshOptions mesh;
  /// A head jump of more than this (m, rad) within one substep is a teleport: the hair goes with the head
  /// rigidly (HeadMotionEstimator::setTeleportLimits); the node's ~teleport_distance, ~teleport_angle.
  double teleport_distance = 0.5;
  double teleport_angle = 1.0;
  /// Read before every substep and every output frame (a signal handler may set it): when it is not 0, run
  /// stops there and throws RunInterrupted.
  const volatile std::sig_atomic_t* interrupted = nullptr;
};

/// Thrown by OfflineRunner::run when RunOptions::interrupted is set: `signal` is its value, `t` the time (s)
/// the run had reached.
struct RunInterrupted : std::runtime_error {
  RunInterrupted(int signal_number, double reached);
  int signal;
  double t;
};

class OfflineRunner {
 public:
  /// Throws std::invalid_argument if a body's frame is neither the config's head_frame nor its world_frame
  /// (the message starts with the key, "bodies[1].frame: ...": the config's file is not known here).
  OfflineRunner(SimConfig config, Hairstyle hairstyle, Scenario scenario);
  /// Index of the first body whose frame is neither head_frame nor world_frame, -1 if none.
  static int bodyInUnknownFrame(const SimConfig& config);
  /// The head pose at t: the scenario's keyframes turned by the head-motion events.
  Iso3 headPose(double t, const EventSample& events) const;
  /// World pose of every body's frame for a head pose.
  std::vector<Iso3> bodyFrames(const Iso3& head_pose) const;
  /// Steps the whole scenario; calls on_frame at t = 0, 1/output_rate, ... <= duration. A frame at t
  /// shows the state after the last substep whose time is <= t (within 1e-9 s), so output rates that
  /// divide the substep rate see identical states.
  RunSummary run(const std::function<void(const OutputFrame&)>& on_frame,
                 const RunOptions& options = RunOptions{});
  const Simulator& simulator() const { return simulator_; }

 private:
  SimConfig config_;
  Scenario scenario_;
  EventSchedule events_;
  Simulator simulator_;
};

}  // namespace hair_sim
