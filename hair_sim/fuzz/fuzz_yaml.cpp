/// Fuzz entry for the YAML loaders: the parameter file (loadSimConfig), hairstyles (loadHairstyle) and
/// offline scenarios (Scenario::load). The first byte picks the loader (0: config, 1: hairstyle,
/// 2: scenario, modulo 3); the rest is the file's text.
///
/// Expected outcome for bad input: std::invalid_argument (or std::runtime_error) with a message naming
/// the file. Anything else is a bug and aborts: a crash, another exception (a bare YAML::Exception has
/// no file or key in its message), undefined behaviour (under the sanitizers), a hang (libFuzzer's
/// -timeout) or an accepted file whose values are not finite or do not hold up in use (an accepted
/// hairstyle is stepped a few substeps, an accepted scenario is sampled over its duration).
///
/// Built twice: with clang and libFuzzer (HAIR_SIM_FUZZ=ON, ./run.sh fuzz) and with the normal compiler
/// and fuzz_replay_main.cpp, which feeds it every file of test/fuzz_corpus/yaml (CTest FuzzReplay_yaml).
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <yaml-cpp/exceptions.h>

#include "hair_sim/core/Simulator.hpp"
#include "hair_sim/core/model/HairstyleIO.hpp"
#include "hair_sim/core/model/SimConfig.hpp"
#include "hair_sim/tools/Scenario.hpp"

namespace {

using namespace hair_sim;

[[noreturn]] void bug(const std::string& what) {
  std::fprintf(stderr, "fuzz_yaml: BUG: %s\n", what.c_str());
  std::fflush(stderr);
  std::abort();
}

void requireFinite(bool ok, const std::string& what) {
  if (!ok) bug("accepted with a non-finite value: " + what);
}

/// A message that names the file (the loaders' contract); an empty or anonymous one is a bug.
void requireNamedMessage(const std::exception& e, const std::string& path) {
  const std::string m = e.what();
  if (m.find(path) == std::string::npos) bug("error message does not name the file: '" + m + "'");
}

void checkEllipsoid(const Ellipsoid& e, const std::string& what) {
  requireFinite(e.center().allFinite() && e.radii().allFinite() && e.S().allFinite() && e.Sinv().allFinite(),
                what);
}

void checkConfig(const SimConfig& c) {
  const PhysicsParameters& p = c.physics;
  requireFinite(std::isfinite(c.publish_rate) && p.gravity.allFinite() && std::isfinite(p.substep) &&
                    std::isfinite(p.linear_density) && std::isfinite(p.hinge_stiffness) &&
                    std::isfinite(p.hinge_damping) && std::isfinite(p.air_drag) &&
                    std::isfinite(p.max_angle_step) && std::isfinite(p.max_bend) &&
                    std::isfinite(p.collision_stiffness) && std::isfinite(p.collision_damping) &&
                    std::isfinite(p.spring_stiffness) && std::isfinite(p.spring_proximity_factor) &&
                    std::isfinite(p.spring_contact_fraction) && std::isfinite(p.spring_far_factor) &&
                    std::isfinite(p.spring_radius),
                "physics");
  try {
    p.validate();
  } catch (const std::exception& e) {
    bug(std::string("loadSimConfig accepted physics that PhysicsParameters::validate rejects: ") + e.what());
  }
  for (const Body& b : c.bodies) checkEllipsoid(b.shape, "body " + b.name);
}

void checkHairstyle(const Hairstyle& h) {
  checkEllipsoid(h.scalp, "scalp");
  if (h.controlPointCount() > 4000) return;  // keep an execution short
  std::unique_ptr<Simulator> sim;
  try {
    sim = std::make_unique<Simulator>(h, PhysicsParameters{});
  } catch (const std::invalid_argument&) {
    return;  // refused with a message where the node and the runner build it: fine
  }
  StepInputs in;
  for (int i = 0; i < 3; ++i) sim->step(in);
  for (const Vec3& p : sim->positionsHead()) requireFinite(p.allFinite(), "hairstyle after 3 substeps");
}

void checkScenario(const Scenario& s) {
  requireFinite(std::isfinite(s.duration) && std::isfinite(s.output_rate), "duration, output_rate");
  const EventSchedule schedule = s.schedule();
  const Vec3 g(0.0, 0.0, -9.81);
  std::vector<double> times;
  for (int i = 0; i <= 16; ++i) times.push_back(s.duration * i / 16.0);
  for (std::size_t i = 1; i < s.head.size() && i < 64; ++i) {  // between keyframes, where tangents act
    times.push_back(0.5 * (s.head[i - 1].t + s.head[i].t));
    times.push_back(s.head[i - 1].t + 0.1 * (s.head[i].t - s.head[i - 1].t));
  }
  for (const double t : times) {
    const Iso3 pose = s.headPose(t);
    requireFinite(pose.matrix().allFinite(), "head pose at t = " + std::to_string(t));
    requireFinite(s.windVelocity(t).allFinite(), "wind at t = " + std::to_string(t));
    const EventSample e = schedule.sample(t, g);
    requireFinite(e.wind.allFinite() && e.gravity.allFinite() && e.head_rotation.allFinite(),
                  "events at t = " + std::to_string(t));
    requireFinite(e.turbulence.at(pose.translation()).allFinite(), "turbulence at t = " + std::to_string(t));
  }
}

std::string scratchPath() {
  const char* dir = std::getenv("TMPDIR");
  return std::string(dir && *dir ? dir : "/tmp") + "/hair_sim_fuzz_yaml_" + std::to_string(getpid()) +
         ".yaml";
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  // The scratch file, removed when the fuzzer or the replay exits.
  static const struct Scratch {
    std::string path = scratchPath();
    ~Scratch() { std::remove(path.c_str()); }
  } scratch;
  const std::string& path = scratch.path;
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data + 1), static_cast<std::streamsize>(size - 1));
    if (!out) bug("cannot write " + path);
  }
  const int which = data[0] % 3;
  try {
    if (which == 0) checkConfig(loadSimConfig(path));
    if (which == 1) checkHairstyle(loadHairstyle(path));
    if (which == 2) checkScenario(Scenario::load(path));
  } catch (const YAML::Exception& e) {
    // A runtime_error too, but its message names neither the file nor the key.
    bug(std::string("YAML::Exception escaped the loader: ") + e.what());
  } catch (const std::invalid_argument& e) {
    requireNamedMessage(e, path);
  } catch (const std::runtime_error& e) {
    requireNamedMessage(e, path);
  } catch (const std::exception& e) {
    bug(std::string("unexpected exception: ") + e.what());
  }
  return 0;
}
