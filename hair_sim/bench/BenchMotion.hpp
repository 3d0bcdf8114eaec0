#pragma once
/// The step benchmarks' hairstyle and motion (BM_Step, BM_MeshBuild, hair_sim_step_profile): generated strips
/// of 2 x 5 control points on the default config's head, the head nodding and turning in a steady wind.
#include <algorithm>
#include <cmath>
#include <vector>

#include "hair_sim/core/Simulator.hpp"
#include "hair_sim/core/model/HairstyleGenerator.hpp"
#include "hair_sim/core/model/SimConfig.hpp"

namespace hair_sim {
namespace bench {

/// The head's rest pose of the benchmarks.
inline Iso3 benchRestPose() {
  Iso3 rest = Iso3::Identity();
  rest.translation() = Vec3(0.0, 0.0, 1.6);
  return rest;
}

/// `strips` generated strips on the head at its rest pose (0, 0, 1.6).
inline Hairstyle benchHairstyle(const SimConfig& config, int strips) {
  GeneratorOptions options;
  options.strips = strips;
  options.rings = std::max(5, static_cast<int>(std::sqrt(strips / 4.0)));
  return generateHairstyle(config, benchRestPose(), options);
}

/// The inputs of substep n: the head nodding and turning in a steady wind, the bodies on the head moving with
/// it; `pose` gets the head pose.
inline StepInputs benchInputs(const SimConfig& config, const Iso3& rest, HeadMotionEstimator& head, long n,
                              double dt, Iso3& pose) {
  pose = rest;
  pose.linear() = rotationFromRpy(Vec3(0.0, 0.2 * std::sin(3.0 * n * dt), 0.6 * std::sin(2.0 * n * dt)));
  StepInputs in;
  in.head = head.update(pose, dt);
  in.wind = Vec3(1.5, 1.0, 0.0);
  for (const Body& b : config.bodies)
    in.body_frames.push_back(b.frame == config.head_frame ? pose : Iso3::Identity());
  return in;
}

/// A Simulator of `strips` benchmark strips on `config` going through the motion of benchInputs, substep
/// after substep: next() gives the inputs of the next substep (and keeps its head pose and body frames),
/// step() takes it. The construction runs `warmup` substeps.
struct MotionRun {
  SimConfig config;
  Iso3 rest = benchRestPose();
  Simulator sim;
  HeadMotionEstimator head;
  long n = 0;                     ///< substeps so far
  Iso3 pose = Iso3::Identity();   ///< the head pose of substep n
  std::vector<Iso3> body_frames;  ///< the bodies' frames of substep n

  MotionRun(const SimConfig& c, int strips, Simulator::StepPath path, int threads, long warmup)
      : config(c), sim(benchHairstyle(c, strips), c.physics, c.bodies) {
    sim.setStepPath(path);
    sim.setThreads(threads);
    head.reset(rest);
    while (n < warmup) step();
  }
  StepInputs next() {
    ++n;
    StepInputs in = benchInputs(config, rest, head, n, config.physics.substep, pose);
    body_frames = in.body_frames;
    return in;
  }
  void step() { sim.step(next()); }
};

}  // namespace bench
}  // namespace hair_sim
