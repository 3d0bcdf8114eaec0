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

#include <sys/stat.h>

#include "hair_sim/core/geometry/PlyWriter.hpp"
#include "hair_sim/core/model/HairstyleIO.hpp"
#include "hair_sim/ros/BagWriter.hpp"
#include "hair_sim/tools/OfflineRunner.hpp"

namespace {

const char* kUsage =
    "Usage: hair_sim_offline --config FILE --scenario FILE [--out FILE.csv] [--poses-out FILE.csv]\n"
    "                        [--mesh-out DIR] [--bag FILE.bag]\n"
    "                        [--samples-across N --samples-along N | --max-triangles N]\n"
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
    "ns_per_control_point_update, ...). Exit status 0 on success, 1 on a bad file or value, 2 on\n"
    "bad usage.\n";

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
    try {
      std::size_t used = 0;
      out = std::stoll(text, &used);
      return used == text.size() && out > 0;
    } catch (const std::exception&) {
      return false;
    }
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
    try {
      std::size_t used = 0;
      out = std::stod(text, &used);
      return used == text.size() && std::isfinite(out) && out > 0.0;
    } catch (const std::exception&) {
      return false;
    }
  };
  if (!teleport_distance.empty() && !positiveReal(teleport_distance, options.teleport_distance))
    return usageError("--teleport-distance: '" + teleport_distance + "' is not a number > 0 (m)");
  if (!teleport_angle.empty() && !positiveReal(teleport_angle, options.teleport_angle))
    return usageError("--teleport-angle: '" + teleport_angle + "' is not a number > 0 (rad)");
  options.build_meshes = !mesh_dir.empty() || !bag_path.empty();

  try {
    hair_sim::SimConfig config = hair_sim::loadSimConfig(config_path);
    hair_sim::Hairstyle style = hair_sim::loadHairstyle(config.hairstyle_file);
    hair_sim::Scenario scenario = hair_sim::Scenario::load(scenario_path);

    std::FILE* out = nullptr;
    if (!out_path.empty()) {
      out = std::fopen(out_path.c_str(), "w");
      if (!out) throw std::runtime_error(out_path + ": cannot open for writing: " + std::strerror(errno));
      std::fputs("t,strip,column,row,x,y,z\n", out);
    }
    std::FILE* poses = nullptr;
    if (!poses_path.empty()) {
      poses = std::fopen(poses_path.c_str(), "w");
      if (!poses) throw std::runtime_error(poses_path + ": cannot open for writing: " + std::strerror(errno));
      std::fputs("t,x,y,z,qx,qy,qz,qw\n", poses);
    }
    if (!mesh_dir.empty() && mkdir(mesh_dir.c_str(), 0755) != 0 && errno != EEXIST)
      throw std::runtime_error(mesh_dir + ": cannot create the folder: " + std::strerror(errno));
    hair_sim::OfflineRunner runner(config, std::move(style), scenario);
    std::unique_ptr<hair_sim::BagWriter> bag;
    if (!bag_path.empty()) bag = std::make_unique<hair_sim::BagWriter>(bag_path, config);
    Progress progress(scenario.duration);
    long frame_number = 0;
    const hair_sim::RunSummary summary = runner.run(
        [&](const hair_sim::OutputFrame& frame) {
          progress.update(frame.t);
          if (bag) bag->write(frame, runner.bodyFrames(frame.head_pose));
          if (!mesh_dir.empty()) {  // (--bag alone builds meshes too, but writes no PLY)
            char name[32];
            std::snprintf(name, sizeof(name), "/frame_%05ld.ply", frame_number);
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
                std::fprintf(out, "%.6f,%zu,%d,%d,%.9g,%.9g,%.9g\n", frame.t, s, c, r, p.x(), p.y(), p.z());
              }
          }
          if (poses) {
            const Eigen::Quaterniond q(frame.head_pose.linear());
            const hair_sim::Vec3 p = frame.head_pose.translation();
            std::fprintf(poses, "%.6f,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n", frame.t, p.x(), p.y(), p.z(),
                         q.x(), q.y(), q.z(), q.w());
          }
        },
        options);
    progress.finish();
    const bool write_ok = (!out || std::fclose(out) == 0) && (!poses || std::fclose(poses) == 0);
    if (!write_ok) throw std::runtime_error("error while writing the output files");
    std::string written;
    for (const std::string& p : {out_path, bag_path, mesh_dir})
      if (!p.empty()) written += (written.empty() ? "" : ", ") + p;
    if (bag) {
      bag->close();
      written += " (" + std::to_string(bag->messagesWritten()) + " messages in the bag)";
    }
    std::cerr << "hair_sim_offline: " << summary.strips << " strips, " << summary.control_points
              << " control points, " << summary.steps << " substeps, " << summary.output_frames
              << " frames written to " << written << "\n";
    std::cout << summary.toJson() << std::endl;
    return summary.all_finite ? 0 : 1;
  } catch (const std::exception& e) {
    std::cerr << "hair_sim_offline: error: " << e.what() << "\n";
    return 1;
  }
}
