/// hair_sim_step_profile: BM_Step's hairstyle and motion for a fixed number of substeps, for profilers that
/// count (callgrind, perf stat) and for checking that a change keeps the simulation's bits.
///
///   hair_sim_step_profile [--strips N] [--warmup N] [--substeps N] [--path lanes|avx2|baseline|exact]
///                         [--threads N] [--config FILE]
///
/// Runs --warmup substeps (default 480: 2 s, the hair moving and lying on the bodies), then --substeps
/// (default 100) more, each through step_profile_measured() (a function of its own, for
/// `valgrind --tool=callgrind --toggle-collect=step_profile_measured`). Prints one JSON line: strips,
/// control points, ns per control-point update over the measured substeps, the share of strips that took
/// the exact step in them, and state_hash, the FNV-1a hash of every control point's position (head frame)
/// at the end: the same for the same inputs on any path, thread count or instruction set; and kernel, the
/// instruction set the path's lanes kernel ran with on this CPU (Simulator::kernelInstructionSet).
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <vector>

#include "../test/SimdDump.hpp"
#include "BenchMotion.hpp"

using namespace hair_sim;

extern "C" __attribute__((noinline)) void step_profile_measured(Simulator& sim, const StepInputs& in) {
  sim.step(in);
}

namespace {

const char* const kUsage =
    "usage: hair_sim_step_profile [--strips N] [--warmup N] [--substeps N] [--path "
    "lanes|avx2|baseline|exact] "
    "[--threads N] [--config FILE]\n";

[[noreturn]] void usage(const std::string& why) {
  std::fprintf(stderr, "hair_sim_step_profile: %s\n%s", why.c_str(), kUsage);
  std::exit(2);
}

long number(const char* flag, const char* text, long min, long max) {
  char* end = nullptr;
  const long value = std::strtol(text, &end, 10);
  if (end == text || *end != '\0' || value < min || value > max)
    usage(std::string(flag) + " wants a whole number in [" + std::to_string(min) + ", " +
          std::to_string(max) + "], got '" + text + "'");
  return value;
}

}  // namespace

int main(int argc, char** argv) {
  long strips = 1000, warmup = 480, substeps = 100, threads = 1;
  Simulator::StepPath path = Simulator::StepPath::Lanes;
  std::string path_name = "lanes";
  std::string config_file = std::string(HAIR_SIM_REPO_ROOT) + "/config/hair_sim.yaml";
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (flag == "--help" || flag == "-h") {
      std::fputs(kUsage, stdout);
      return 0;
    }
    if (i + 1 >= argc) usage(flag + " needs a value");
    const char* value = argv[++i];
    if (flag == "--strips")
      strips = number("--strips", value, 1, 1000000);
    else if (flag == "--warmup")
      warmup = number("--warmup", value, 0, 100000000);
    else if (flag == "--substeps")
      substeps = number("--substeps", value, 1, 100000000);
    else if (flag == "--threads")
      threads = number("--threads", value, 1, 64);
    else if (flag == "--config")
      config_file = value;
    else if (flag == "--path") {
      path_name = value;
      if (path_name == "lanes")
        path = Simulator::StepPath::Lanes;
      else if (path_name == "baseline")
        path = Simulator::StepPath::LanesBaseline;
      else if (path_name == "avx2")
        path = Simulator::StepPath::LanesAvx2;
      else if (path_name == "exact")
        path = Simulator::StepPath::Exact;
      else
        usage("--path wants lanes, avx2, baseline or exact, got '" + path_name + "'");
    } else {
      usage("unknown option '" + flag + "'");
    }
  }
  try {
    const SimConfig config = loadSimConfig(config_file);
    bench::MotionRun run(config, static_cast<int>(strips), path, static_cast<int>(threads), warmup);
    Simulator& sim = run.sim;
    double exact = 0.0, seconds = 0.0;
    for (long k = 0; k < substeps; ++k) {
      const StepInputs in = run.next();
      const auto t0 = std::chrono::steady_clock::now();
      step_profile_measured(sim, in);
      seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      exact += sim.exactStripCount();
    }
    // FNV-1a over the positions' bytes (contiguous: Vec3 is three doubles).
    const std::vector<Vec3>& positions = sim.positionsHead();
    const std::uint64_t hash = simd_dump::hashOf(positions.data(), positions.size() * sizeof(Vec3));
    const double strip_count = static_cast<double>(sim.hairstyle().strips.size());
    std::printf(
        "{\"strips\": %ld, \"control_points\": %d, \"path\": \"%s\", \"threads\": %ld, \"warmup\": %ld, "
        "\"substeps\": %ld, \"ns_per_update\": %.1f, \"exact_share\": %.4f, \"state_hash\": \"%016llx\", "
        "\"kernel\": \"%s\"}\n",
        strips, sim.controlPointCount(), path_name.c_str(), threads, warmup, substeps,
        1e9 * seconds / (static_cast<double>(substeps) * sim.controlPointCount()),
        exact / (static_cast<double>(substeps) * strip_count), static_cast<unsigned long long>(hash),
        Simulator::kernelInstructionSet(sim.stepPath()));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hair_sim_step_profile: %s\n", e.what());
    return 1;
  }
  return 0;
}
