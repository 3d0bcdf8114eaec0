#include "hair_sim/tools/OfflineRunner.hpp"

#include <chrono>
#include <cmath>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "hair_sim/core/util/YamlReader.hpp"

namespace hair_sim {

std::string RunSummary::toJson() const {
  std::ostringstream o;
  o << "{\"steps\": " << steps << ", \"control_points\": " << control_points << ", \"strips\": " << strips
    << ", \"output_frames\": " << output_frames << ", \"sim_seconds\": " << formatDouble(sim_seconds)
    << ", \"wall_seconds\": " << formatDouble(wall_seconds)
    << ", \"ns_per_control_point_update\": " << formatDouble(ns_per_control_point_update)
    << ", \"max_segment_rate\": " << formatDouble(max_segment_rate)
    << ", \"max_penetration_m\": " << formatDouble(max_penetration_m)
    << ", \"min_strip_gap_m\": " << formatDouble(min_strip_gap_m)
    << ", \"max_width_ratio\": " << formatDouble(max_width_ratio) << ", \"collisions\": " << collisions
    << ", \"max_mesh_penetration_m\": " << formatDouble(max_mesh_penetration_m)
    << ", \"mesh_vertices_projected\": " << mesh_vertices_projected
    << ", \"mesh_vertices\": " << mesh_vertices << ", \"mesh_triangles\": " << mesh_triangles
    << ", \"all_finite\": " << (all_finite ? "true" : "false") << ", \"teleports\": " << teleports << "}";
  return o.str();
}

OfflineRunner::OfflineRunner(SimConfig config, Hairstyle hairstyle, Scenario scenario)
    : config_(std::move(config)),
      scenario_(std::move(scenario)),
      events_(scenario_.schedule()),
      simulator_(std::move(hairstyle), config_.physics, config_.bodies) {
  const int b = bodyInUnknownFrame(config_);
  if (b >= 0) {
    const Body& body = config_.bodies[static_cast<std::size_t>(b)];
    throw std::invalid_argument("bodies[" + std::to_string(b) + "].frame: body '" + body.name +
                                "' is in frame '" + body.frame +
                                "': the offline runner knows only head_frame '" + config_.head_frame +
                                "' and world_frame '" + config_.world_frame + "'");
  }
}

int OfflineRunner::bodyInUnknownFrame(const SimConfig& config) {
  for (std::size_t b = 0; b < config.bodies.size(); ++b)
    if (config.bodies[b].frame != config.head_frame && config.bodies[b].frame != config.world_frame)
      return static_cast<int>(b);
  return -1;
}

Iso3 OfflineRunner::headPose(double t, const EventSample& events) const {
  Iso3 pose = scenario_.headPose(t);
  pose.linear() = pose.linear() * events.head_rotation;
  return pose;
}

std::vector<Iso3> OfflineRunner::bodyFrames(const Iso3& head_pose) const {
  std::vector<Iso3> frames;
  for (const Body& b : config_.bodies)
    frames.push_back(b.frame == config_.head_frame ? head_pose : Iso3::Identity());
  return frames;
}

RunInterrupted::RunInterrupted(int signal_number, double reached)
    : std::runtime_error("interrupted by signal " + std::to_string(signal_number) +
                         " at t = " + formatDouble(reached) + " s"),
      signal(signal_number),
      t(reached) {}

RunSummary OfflineRunner::run(const std::function<void(const OutputFrame&)>& on_frame,
                              const RunOptions& options) {
  const double dt = config_.physics.substep;
  simulator_.reset();
  HeadMotionEstimator head;
  head.setTeleportLimits(options.teleport_distance, options.teleport_angle);
  head.reset(headPose(0.0, events_.sample(0.0, config_.physics.gravity)));
  std::vector<Vec3> world;
  RunSummary summary;
  summary.control_points = simulator_.controlPointCount();
  summary.strips = static_cast<int>(simulator_.hairstyle().strips.size());
  const long frames = static_cast<long>(std::floor(scenario_.duration * scenario_.output_rate + 1e-9));
  long n = 0;  // substeps done; the state is at time n * dt
  double stepping_seconds = 0.0;
  std::unique_ptr<HairMeshBuilder> meshes;
  if (options.build_meshes) meshes = std::make_unique<HairMeshBuilder>(simulator_.hairstyle(), options.mesh);
  for (long f = 0; f <= frames; ++f) {
    const double t_frame = static_cast<double>(f) / scenario_.output_rate;
    const auto start = std::chrono::steady_clock::now();
    while (static_cast<double>(n + 1) * dt <= t_frame + 1e-9) {
      if (options.interrupted && *options.interrupted != 0)
        throw RunInterrupted(*options.interrupted, static_cast<double>(n) * dt);
      ++n;
      const double t = static_cast<double>(n) * dt;
      StepInputs in;
      const EventSample events = events_.sample(t, config_.physics.gravity);
      in.head = head.update(headPose(t, events), dt);
      if (head.teleported()) {
        simulator_.forgetBodyMotion();
        ++summary.teleports;
      }
      in.wind = scenario_.windVelocity(t) + events.wind;
      in.turbulence = &events.turbulence;
      in.gravity = &events.gravity;
      in.body_frames = bodyFrames(in.head.pose);
      simulator_.step(in);
      summary.max_segment_rate = std::max(summary.max_segment_rate, simulator_.maxSegmentRate());
      summary.max_penetration_m = std::max(summary.max_penetration_m, simulator_.maxPenetration());
      if (!simulator_.springs().empty())
        summary.min_strip_gap_m =
            n == 1 ? simulator_.minStripGap() : std::min(summary.min_strip_gap_m, simulator_.minStripGap());
      summary.max_width_ratio = std::max(summary.max_width_ratio, simulator_.maxSpringRatio(true));
      summary.collisions += simulator_.collisionCount();
    }
    stepping_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    simulator_.positionsWorld(head.state().pose, world);
    for (const Vec3& p : world) summary.all_finite = summary.all_finite && p.allFinite();
    if (meshes) {
      const Iso3& pose = head.state().pose;
      const std::vector<Iso3> frames = bodyFrames(pose);
      std::vector<Ellipsoid> bodies;
      for (std::size_t b = 0; b < config_.bodies.size(); ++b)
        bodies.push_back(config_.bodies[b].shape.transformed(frames[b]));
      meshes->build(world, simulator_.stripOffsets(), simulator_.hairstyle().scalp.transformed(pose), bodies);
      summary.mesh_vertices_projected += meshes->projectedVertices();
      summary.max_mesh_penetration_m =
          std::max(summary.max_mesh_penetration_m, meshes->maxPenetration(bodies));
      summary.mesh_vertices = meshes->vertexCount();
      summary.mesh_triangles = meshes->triangleCount();
    }
    if (on_frame) {
      OutputFrame frame;
      frame.t = t_frame;
      frame.head_pose = head.state().pose;
      frame.points_world = &world;
      frame.simulator = &simulator_;
      frame.meshes = meshes.get();
      if (options.interrupted && *options.interrupted != 0)
        throw RunInterrupted(*options.interrupted, static_cast<double>(n) * dt);
      on_frame(frame);
    }
    ++summary.output_frames;
  }
  summary.steps = n;
  summary.sim_seconds = static_cast<double>(n) * dt;
  summary.wall_seconds = stepping_seconds;
  const double updates = static_cast<double>(n) * summary.control_points;
  summary.ns_per_control_point_update = updates > 0 ? stepping_seconds * 1e9 / updates : 0.0;
  return summary;
}

}  // namespace hair_sim
