/// hair_sim_offline: runs the hair core on a scenario without a ROS master; can bake the run into a rosbag.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <sys/stat.h>
#include <climits>
#include <csignal>
#include <cstdlib>

#include "hair_sim/core/geometry/PlyWriter.hpp"
#include "hair_sim/core/model/HairstyleIO.hpp"
#include "hair_sim/core/util/YamlReader.hpp"
#include "hair_sim/ros/BagWriter.hpp"
#include "hair_sim/tools/Arguments.hpp"
#include "hair_sim/tools/OfflineRunner.hpp"

namespace {

const char* kUsage =
    "Usage: hair_sim_offline --config FILE --scenario FILE [--out FILE.csv] [--poses-out FILE.csv]\n"
    "                        [--mesh-out DIR] [--bag FILE.bag]\n"
    "                        [--samples-across N --samples-along N | --max-triangles N]\n"
    "                        [--teleport-distance M] [--teleport-angle RAD]\n"
    "\n"
    "Runs the hair simulation core (no ROS master needed) on a scenario and writes every control\n"
    "point of every output frame (--out), or bakes the run into a rosbag (--bag), or both.\n"
    "\n"
    "  --config FILE       parameter YAML (as the node loads it: physics, world_frame, head_frame,\n"
    "                      hairstyle path relative to this file)\n"
    "  --scenario FILE     scenario YAML: duration, output_rate, head keyframes, wind keyframes,\n"
    "                      events\n"
    "  --out FILE.csv      control points, header t,strip,column,row,x,y,z (world frame, m)\n"
    "  --bag FILE.bag      bake the run: /tf, /hair_markers, /collision_bodies (latched), /hair_state\n"
    "                      at bag time 1 s + t, one of each per output frame; view it with\n"
    "                      rosbag play plus the shipped rviz config (config/hair_sim.rviz)\n"
    "  --poses-out FILE    head pose per output frame, header t,x,y,z,qx,qy,qz,qw\n"
    "  --mesh-out DIR      one binary PLY per output frame (DIR/frame_00000.ply, ...): the tessellated\n"
    "                      strips, world frame, positions, normals and RGBA (both faces); opens in\n"
    "                      Blender and MeshLab\n"
    "  --samples-across N  level of detail: mesh samples per B-spline span across a strip (default 2)\n"
    "  --samples-along N   level of detail: mesh samples per span along a strip (default 4)\n"
    "  --max-triangles N   choose the finest level of detail within N triangles instead\n"
    "  --teleport-distance M, --teleport-angle RAD\n"
    "                      a head jump beyond these within one substep is a teleport: the hair goes with\n"
    "                      the head rigidly (default 0.5 m, 1.0 rad, as the node)\n"
    "  --help              this text\n"
    "\n"
    "A progress bar goes to stderr when it is a terminal and the run takes more than a second.\n"
    "The last line on stdout is a JSON summary (steps, control_points, sim_seconds, wall_seconds,\n"
    "ns_per_control_point_update, ...). Exit status 0 on success, 1 on a bad file or value, a failed\n"
    "write or a non-finite result, 2 on bad usage. Every input is checked before any output is opened;\n"
    "when writing fails mid-run, or Ctrl-C (SIGINT) or SIGTERM stops it, the incomplete output files of\n"
    "the run are removed (exit status 130 or 143).\n";

/// A progress bar on stderr: only when stderr is a terminal, and only once the run has taken a
/// second (short runs stay quiet); redrawn at most ten times a second.
class Progress {
 public:
  explicit Progress(double total) : total_(total), enabled_(isatty(STDERR_FILENO) == 1) {}
  void update(double t) {
    if (!enabled_) return;
    const auto now = std::chrono::steady_clock::now();
    if (now - start_ < std::chrono::seconds(1) || now - last_ < std::chrono::milliseconds(100)) return;
    last_ = now;
    const double f = total_ > 0.0 ? std::min(1.0, t / total_) : 1.0;
    const int filled = static_cast<int>(f * 30.0);
    std::fprintf(stderr, "\rhair_sim_offline: [%s%s] %3d%%  t = %.2f / %.2f s",
                 std::string(filled, '#').c_str(), std::string(30 - filled, '-').c_str(),
                 static_cast<int>(100.0 * f), t, total_);
    std::fflush(stderr);
    drawn_ = true;
  }
  void finish() {
    if (drawn_) std::fprintf(stderr, "\n");
  }

 private:
  double total_;
  bool enabled_;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  std::chrono::steady_clock::time_point last_{};
};

int usageError(const std::string& message) {
  std::cerr << "hair_sim_offline: " << message << "\n\n" << kUsage;
  return 2;
}

std::string parentFolder(const std::string& path) {
  const std::size_t slash = path.rfind('/');
  if (slash == std::string::npos) return ".";
  return slash == 0 ? "/" : path.substr(0, slash);
}

std::string withoutTrailingSlashes(std::string path) {
  while (path.size() > 1 && path.back() == '/') path.pop_back();
  return path;
}

/// What identifies an output path, for refusing one file given to two outputs: the canonical path of
/// the file, or of its folder plus its name when it does not exist yet. Empty for existing special files
/// (/dev/null may well take several outputs).
std::string outputIdentity(const std::string& given) {
  const std::string path = withoutTrailingSlashes(given);
  struct stat st {};
  if (stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode) && !S_ISDIR(st.st_mode)) return "";
  char resolved[PATH_MAX];
  if (realpath(path.c_str(), resolved)) return resolved;
  const std::string folder = parentFolder(path);
  const std::string name = path.substr(path.rfind('/') == std::string::npos ? 0 : path.rfind('/') + 1);
  return (realpath(folder.c_str(), resolved) ? std::string(resolved) : folder) + "/" + name;
}

/// Why the file `path` cannot be created or overwritten ("" if it can). Checked before any output is
/// opened so that a run refused for one output truncates none of the others.
std::string cannotWriteFile(const std::string& path) {
  struct stat st {};
  if (stat(path.c_str(), &st) == 0) {
    if (S_ISDIR(st.st_mode)) return std::strerror(EISDIR);
    return access(path.c_str(), W_OK) == 0 ? "" : std::strerror(errno);
  }
  if (errno != ENOENT) return std::strerror(errno);
  return access(parentFolder(path).c_str(), W_OK | X_OK) == 0 ? "" : std::strerror(errno);
}

/// The same for a folder that is used or created.
std::string cannotWriteFolder(const std::string& given) {
  const std::string dir = withoutTrailingSlashes(given);
  struct stat st {};
  if (stat(dir.c_str(), &st) == 0) {
    if (!S_ISDIR(st.st_mode)) return std::strerror(ENOTDIR);
    return access(dir.c_str(), W_OK | X_OK) == 0 ? "" : std::strerror(errno);
  }
  if (errno != ENOENT) return std::strerror(errno);
  return access(parentFolder(dir).c_str(), W_OK | X_OK) == 0 ? "" : std::strerror(errno);
}

/// The signal (SIGINT, SIGTERM) that asked the run to stop, 0 while none did; the runner reads it between
/// substeps, so that the incomplete outputs are removed before the program ends.
volatile std::sig_atomic_t g_interrupted = 0;

extern "C" void onStopSignal(int signal_number) { g_interrupted = signal_number; }

/// A failed write: names the file and the reason (errno of the failed call).
[[noreturn]] void writeFailed(const std::string& path) {
  const int err = errno != 0 ? errno : EIO;
  throw std::runtime_error(path + ": cannot write: " + std::strerror(err));
}

/// The files a run created or truncated, removed when the run fails half way so that no incomplete
/// output is left looking like a result. Special files (/dev/null, FIFOs) are not registered.
class PartialOutputs {
 public:
  void addFile(const std::string& path) {
    struct stat st {};
    if (stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode)) files_.push_back(path);
  }
  void addPly(const std::string& path) { plys_.push_back(path); }
  void setCreatedFolder(const std::string& dir) { created_folder_ = dir; }
  void removeAll() {
    for (const std::string& f : files_)
      if (std::remove(f.c_str()) == 0) std::cerr << "hair_sim_offline: removed the incomplete " << f << "\n";
    int removed = 0;
    for (const std::string& f : plys_) removed += std::remove(f.c_str()) == 0 ? 1 : 0;
    if (removed > 0)
      std::cerr << "hair_sim_offline: removed the " << removed << " PLY files of this run from "
                << parentFolder(plys_.front()) << "\n";
    if (!created_folder_.empty() && rmdir(created_folder_.c_str()) == 0)
      std::cerr << "hair_sim_offline: removed the folder " << created_folder_ << "\n";
    files_.clear();
    plys_.clear();
    created_folder_.clear();
  }

 private:
  std::vector<std::string> files_;
  std::vector<std::string> plys_;
  std::string created_folder_;
};

}  // namespace

int main(int argc, char** argv) {
  std::string config_path, scenario_path, out_path, poses_path, mesh_dir, bag_path;
  hair_sim::RunOptions options;
  std::string across, along, max_triangles, teleport_distance, teleport_angle;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&](std::string& target) {
      if (i + 1 >= argc) return false;
      target = argv[++i];
      return true;
    };
    if (arg == "--help" || arg == "-h") {
      std::cout << kUsage;
      return 0;
    } else if (arg == "--config") {
      if (!value(config_path)) return usageError("--config needs a file");
    } else if (arg == "--scenario") {
      if (!value(scenario_path)) return usageError("--scenario needs a file");
    } else if (arg == "--out") {
      if (!value(out_path)) return usageError("--out needs a file");
    } else if (arg == "--poses-out") {
      if (!value(poses_path)) return usageError("--poses-out needs a file");
    } else if (arg == "--bag") {
      if (!value(bag_path)) return usageError("--bag needs a file");
    } else if (arg == "--mesh-out") {
      if (!value(mesh_dir)) return usageError("--mesh-out needs a folder");
    } else if (arg == "--samples-across") {
      if (!value(across)) return usageError("--samples-across needs a number");
    } else if (arg == "--samples-along") {
      if (!value(along)) return usageError("--samples-along needs a number");
    } else if (arg == "--max-triangles") {
      if (!value(max_triangles)) return usageError("--max-triangles needs a number");
    } else if (arg == "--teleport-distance") {
      if (!value(teleport_distance)) return usageError("--teleport-distance needs a number");
    } else if (arg == "--teleport-angle") {
      if (!value(teleport_angle)) return usageError("--teleport-angle needs a number");
    } else {
      return usageError("unknown argument '" + arg + "'");
    }
  }
  if (config_path.empty()) return usageError("--config is required");
  if (scenario_path.empty()) return usageError("--scenario is required");
  if (out_path.empty() && bag_path.empty() && mesh_dir.empty())
    return usageError("--out, --bag or --mesh-out is required");
  auto positive = [](const std::string& text, long long& out) {
    return hair_sim::parseInteger(text, out) && out > 0;
  };
  long long number = 0;
  if (!across.empty()) {
    if (!positive(across, number) || number > 64)
      return usageError("--samples-across: '" + across + "' is not in 1..64");
    options.mesh.level_of_detail.samples_across = static_cast<int>(number);
  }
  if (!along.empty()) {
    if (!positive(along, number) || number > 64)
      return usageError("--samples-along: '" + along + "' is not in 1..64");
    options.mesh.level_of_detail.samples_along = static_cast<int>(number);
  }
  if (!max_triangles.empty()) {
    if (!positive(max_triangles, number))
      return usageError("--max-triangles: '" + max_triangles + "' is not a positive integer");
    options.mesh.max_triangles = number;
  }
  auto positiveReal = [](const std::string& text, double& out) {
    return hair_sim::parseReal(text, out) && out > 0.0;
  };
  if (!teleport_distance.empty() && !positiveReal(teleport_distance, options.teleport_distance))
    return usageError("--teleport-distance: '" + teleport_distance + "' is not a number > 0 (m)");
  if (!teleport_angle.empty() && !positiveReal(teleport_angle, options.teleport_angle))
    return usageError("--teleport-angle: '" + teleport_angle + "' is not a number > 0 (rad)");
  options.build_meshes = !mesh_dir.empty() || !bag_path.empty();
  {
    const std::pair<const char*, const std::string*> outputs[] = {
        {"--out", &out_path}, {"--poses-out", &poses_path}, {"--bag", &bag_path}, {"--mesh-out", &mesh_dir}};
    for (std::size_t i = 0; i < 4; ++i)
      for (std::size_t j = i + 1; j < 4; ++j) {
        if (outputs[i].second->empty() || outputs[j].second->empty()) continue;
        const std::string id = outputIdentity(*outputs[i].second);
        if (!id.empty() && id == outputIdentity(*outputs[j].second))
          return usageError(std::string(outputs[i].first) + " '" + *outputs[i].second + "' and " +
                            outputs[j].first + " '" + *outputs[j].second + "' are the same file");
      }
  }

  // Everything that can refuse the run is checked before the first output is opened: a refused run
  // creates, truncates and removes nothing.
  std::FILE* out = nullptr;
  std::FILE* poses = nullptr;
  std::unique_ptr<hair_sim::BagWriter> bag;
  PartialOutputs partial;
  double scenario_duration = 0.0;
  auto closeQuietly = [&] {
    if (out) std::fclose(out);
    if (poses) std::fclose(poses);
    out = poses = nullptr;
    bag.reset();  // closes the bag if it can, never throws
  };
  try {
    hair_sim::SimConfig config = hair_sim::loadSimConfig(config_path);
    hair_sim::Hairstyle style = hair_sim::loadHairstyle(config.hairstyle_file);
    hair_sim::Scenario scenario = hair_sim::Scenario::load(scenario_path);
    scenario_duration = scenario.duration;
    const int unknown_frame = hair_sim::OfflineRunner::bodyInUnknownFrame(config);
    if (unknown_frame >= 0) {
      const hair_sim::Body& b = config.bodies[static_cast<std::size_t>(unknown_frame)];
      throw hair_sim::YamlReader::loadFile(config_path)
          .child("bodies")
          .at(static_cast<std::size_t>(unknown_frame))
          .error("frame", "body '" + b.name + "' is in frame '" + b.frame +
                              "': the offline runner knows only head_frame '" + config.head_frame +
                              "' and world_frame '" + config.world_frame + "'");
    }
    if (options.mesh.max_triangles > 0) {
      const std::int64_t minimum = hair_sim::HairMeshBuilder::minimumTriangles(style);
      if (options.mesh.max_triangles < minimum)
        return usageError("--max-triangles: " + max_triangles + " is below the " + std::to_string(minimum) +
                          " triangles of the coarsest level of detail (1 x 1 samples per span) of " +
                          config.hairstyle_file);
    }
    hair_sim::OfflineRunner runner(config, std::move(style), scenario);
    for (const std::string* path : {&out_path, &poses_path, &bag_path}) {
      if (path->empty()) continue;
      const std::string why = cannotWriteFile(*path);
      if (!why.empty()) throw std::runtime_error(*path + ": cannot open for writing: " + why);
    }
    if (!mesh_dir.empty()) {
      const std::string why = cannotWriteFolder(mesh_dir);
      if (!why.empty())
        throw std::runtime_error(mesh_dir + ": cannot write PLY files into the folder: " + why);
    }

    if (!out_path.empty()) {
      out = std::fopen(out_path.c_str(), "w");
      if (!out) throw std::runtime_error(out_path + ": cannot open for writing: " + std::strerror(errno));
      partial.addFile(out_path);
      if (std::fputs("t,strip,column,row,x,y,z\n", out) < 0) writeFailed(out_path);
    }
    if (!poses_path.empty()) {
      poses = std::fopen(poses_path.c_str(), "w");
      if (!poses) throw std::runtime_error(poses_path + ": cannot open for writing: " + std::strerror(errno));
      partial.addFile(poses_path);
      if (std::fputs("t,x,y,z,qx,qy,qz,qw\n", poses) < 0) writeFailed(poses_path);
    }
    if (!mesh_dir.empty()) {
      if (mkdir(mesh_dir.c_str(), 0755) == 0)
        partial.setCreatedFolder(mesh_dir);
      else if (errno != EEXIST)
        throw std::runtime_error(mesh_dir + ": cannot create the folder: " + std::strerror(errno));
    }
    if (!bag_path.empty()) {
      bag = std::make_unique<hair_sim::BagWriter>(bag_path, config);
      partial.addFile(bag_path);
    }
    Progress progress(scenario.duration);
    long frame_number = 0;
    options.interrupted = &g_interrupted;
    struct sigaction stop {};
    stop.sa_handler = onStopSignal;
    sigemptyset(&stop.sa_mask);
    sigaction(SIGINT, &stop, nullptr);
    sigaction(SIGTERM, &stop, nullptr);
    const hair_sim::RunSummary summary = runner.run(
        [&](const hair_sim::OutputFrame& frame) {
          progress.update(frame.t);
          if (bag) bag->write(frame, runner.bodyFrames(frame.head_pose));
          if (!mesh_dir.empty()) {  // (--bag alone builds meshes too, but writes no PLY)
            char name[32];
            std::snprintf(name, sizeof(name), "/frame_%05ld.ply", frame_number);
            partial.addPly(mesh_dir + name);
            hair_sim::PlyWriter::write(mesh_dir + name, frame.meshes->meshes(), frame.meshes->colours());
          }
          ++frame_number;
          const auto& strips = frame.simulator->hairstyle().strips;
          const auto& offsets = frame.simulator->stripOffsets();
          for (std::size_t s = 0; out && s < strips.size(); ++s) {
            for (int r = 0; r < strips[s].rows; ++r)
              for (int c = 0; c < strips[s].columns; ++c) {
                const hair_sim::Vec3& p =
                    (*frame.points_world)[static_cast<std::size_t>(offsets[s] + strips[s].index(r, c))];
                if (std::fprintf(out, "%.6f,%zu,%d,%d,%.9g,%.9g,%.9g\n", frame.t, s, c, r, p.x(), p.y(),
                                 p.z()) < 0)
                  writeFailed(out_path);
              }
          }
          if (out && std::fflush(out) != 0) writeFailed(out_path);
          if (poses) {
            const Eigen::Quaterniond q(frame.head_pose.linear());
            const hair_sim::Vec3 p = frame.head_pose.translation();
            if (std::fprintf(poses, "%.6f,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n", frame.t, p.x(), p.y(), p.z(),
                             q.x(), q.y(), q.z(), q.w()) < 0 ||
                std::fflush(poses) != 0)
              writeFailed(poses_path);
          }
        },
        options);
    progress.finish();
    for (std::pair<std::FILE**, const std::string*> f :
         {std::make_pair(&out, &out_path), std::make_pair(&poses, &poses_path)}) {
      if (!*f.first) continue;
      const int closed = std::fclose(*f.first);
      *f.first = nullptr;
      if (closed != 0) writeFailed(*f.second);
    }
    long bag_messages = 0;
    if (bag) {
      bag->close();
      bag_messages = bag->messagesWritten();
      bag.reset();
    }
    std::string written;
    for (const std::string& p : {out_path, poses_path, bag_path, mesh_dir})
      if (!p.empty()) written += (written.empty() ? "" : ", ") + p;
    if (!bag_path.empty()) written += " (" + std::to_string(bag_messages) + " messages in the bag)";
    std::cerr << "hair_sim_offline: " << summary.strips << " strips, " << summary.control_points
              << " control points, " << summary.steps << " substeps, " << summary.output_frames
              << " frames written to " << written << "\n";
    if (summary.steps == 0)
      std::cerr << "hair_sim_offline: warning: no substep was simulated: with duration "
                << hair_sim::formatDouble(scenario.duration) << " s and output_rate "
                << hair_sim::formatDouble(scenario.output_rate) << " Hz the last output frame is at t = "
                << hair_sim::formatDouble((summary.output_frames - 1) / scenario.output_rate)
                << " s, before the first substep (" << hair_sim::formatDouble(config.physics.substep)
                << " s): the outputs hold the initial state only\n";
    std::cout << summary.toJson() << std::endl;
    return summary.all_finite ? 0 : 1;
  } catch (const hair_sim::RunInterrupted& e) {
    closeQuietly();
    char reached[32];
    std::snprintf(reached, sizeof(reached), "%.3f", e.t);
    std::cerr << (isatty(STDERR_FILENO) == 1 ? "\n" : "")  // below the progress bar
              << "hair_sim_offline: " << strsignal(e.signal) << " at t = " << reached
              << " s of the scenario's " << hair_sim::formatDouble(scenario_duration)
              << " s: the run stopped, and its incomplete outputs are removed\n";
    partial.removeAll();
    return 128 + e.signal;
  } catch (const std::exception& e) {
    closeQuietly();
    std::cerr << "hair_sim_offline: error: " << e.what() << "\n";
    partial.removeAll();
    return 1;
  }
}
