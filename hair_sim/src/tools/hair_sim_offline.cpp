/// hair_sim_offline: runs the hair core on a scenario without a ROS master.
#include <cstdio>
#include <cstring>
#include <exception>
#include <fstream>
#include <iostream>
#include <string>

#include <sys/stat.h>

#include "hair_sim/core/geometry/PlyWriter.hpp"
#include "hair_sim/core/model/HairstyleIO.hpp"
#include "hair_sim/tools/OfflineRunner.hpp"

namespace {

const char* kUsage =
    "Usage: hair_sim_offline --config FILE --scenario FILE --out FILE.csv [--poses-out FILE.csv]\n"
    "                        [--mesh-out DIR] [--samples-across N --samples-along N | --max-triangles N]\n"
    "\n"
    "Runs the hair simulation core (no ROS master needed) on a scenario and writes every control\n"
    "point of every output frame.\n"
    "\n"
    "  --config FILE       parameter YAML (as the node loads it: physics, world_frame, head_frame,\n"
    "                      hairstyle path relative to this file)\n"
    "  --scenario FILE     scenario YAML: duration, output_rate, head keyframes, wind keyframes\n"
    "  --out FILE.csv      control points, header t,strip,column,row,x,y,z (world frame, m)\n"
    "  --poses-out FILE    head pose per output frame, header t,x,y,z,qx,qy,qz,qw\n"
    "  --mesh-out DIR      one binary PLY per output frame (DIR/frame_00000.ply, ...): the tessellated\n"
    "                      strips, world frame, positions, normals and RGBA (both faces); opens in\n"
    "                      Blender and MeshLab\n"
    "  --samples-across N  level of detail: mesh samples per B-spline span across a strip (default 2)\n"
    "  --samples-along N   level of detail: mesh samples per span along a strip (default 4)\n"
    "  --max-triangles N   choose the finest level of detail within N triangles instead\n"
    "  --help              this text\n"
    "\n"
    "The last line on stdout is a JSON summary (steps, control_points, sim_seconds, wall_seconds,\n"
    "ns_per_control_point_update, ...). Exit status 0 on success, 1 on a bad file or value, 2 on\n"
    "bad usage.\n";

int usageError(const std::string& message) {
  std::cerr << "hair_sim_offline: " << message << "\n\n" << kUsage;
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  std::string config_path, scenario_path, out_path, poses_path, mesh_dir;
  hair_sim::RunOptions options;
  std::string across, along, max_triangles;
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
    } else if (arg == "--mesh-out") {
      if (!value(mesh_dir)) return usageError("--mesh-out needs a folder");
    } else if (arg == "--samples-across") {
      if (!value(across)) return usageError("--samples-across needs a number");
    } else if (arg == "--samples-along") {
      if (!value(along)) return usageError("--samples-along needs a number");
    } else if (arg == "--max-triangles") {
      if (!value(max_triangles)) return usageError("--max-triangles needs a number");
    } else {
      return usageError("unknown argument '" + arg + "'");
    }
  }
  if (config_path.empty()) return usageError("--config is required");
  if (scenario_path.empty()) return usageError("--scenario is required");
  if (out_path.empty()) return usageError("--out is required");
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
  options.build_meshes = !mesh_dir.empty();

  try {
    hair_sim::SimConfig config = hair_sim::loadSimConfig(config_path);
    hair_sim::Hairstyle style = hair_sim::loadHairstyle(config.hairstyle_file);
    hair_sim::Scenario scenario = hair_sim::Scenario::load(scenario_path);

    std::FILE* out = std::fopen(out_path.c_str(), "w");
    if (!out) throw std::runtime_error(out_path + ": cannot open for writing: " + std::strerror(errno));
    std::FILE* poses = nullptr;
    if (!poses_path.empty()) {
      poses = std::fopen(poses_path.c_str(), "w");
      if (!poses) throw std::runtime_error(poses_path + ": cannot open for writing: " + std::strerror(errno));
      std::fputs("t,x,y,z,qx,qy,qz,qw\n", poses);
    }
    std::fputs("t,strip,column,row,x,y,z\n", out);
    if (!mesh_dir.empty() && mkdir(mesh_dir.c_str(), 0755) != 0 && errno != EEXIST)
      throw std::runtime_error(mesh_dir + ": cannot create the folder: " + std::strerror(errno));
    hair_sim::OfflineRunner runner(config, std::move(style), scenario);
    long frame_number = 0;
    const hair_sim::RunSummary summary = runner.run(
        [&](const hair_sim::OutputFrame& frame) {
          if (frame.meshes) {
            char name[32];
            std::snprintf(name, sizeof(name), "/frame_%05ld.ply", frame_number);
            hair_sim::PlyWriter::write(mesh_dir + name, frame.meshes->meshes(), frame.meshes->colours());
          }
          ++frame_number;
          const auto& strips = frame.simulator->hairstyle().strips;
          const auto& offsets = frame.simulator->stripOffsets();
          for (std::size_t s = 0; s < strips.size(); ++s) {
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
    const bool write_ok = std::fclose(out) == 0 && (!poses || std::fclose(poses) == 0);
    if (!write_ok) throw std::runtime_error("error while writing the output files");
    std::cerr << "hair_sim_offline: " << summary.strips << " strips, " << summary.control_points
              << " control points, " << summary.steps << " substeps, " << summary.output_frames
              << " frames written to " << out_path << "\n";
    std::cout << summary.toJson() << std::endl;
    return summary.all_finite ? 0 : 1;
  } catch (const std::exception& e) {
    std::cerr << "hair_sim_offline: error: " << e.what() << "\n";
    return 1;
  }
}
