#pragma once
/// Bakes an offline run into a rosbag that `rosbag play` and the shipped rviz config show as the node
/// would have published it: /tf (world_frame -> head_frame), /hair_markers, /collision_bodies
/// (latched, written when a body moved) and /hair_state, at bag time kStart + t.
#include <rosbag/bag.h>

#include <string>
#include <vector>

#include "hair_sim/core/model/SimConfig.hpp"
#include "hair_sim/ros/HairMessages.hpp"
#include "hair_sim/tools/OfflineRunner.hpp"

namespace hair_sim {

class BagWriter {
 public:
  /// Bag time of the scenario's t = 0 (s): rosbag needs times above zero.
  static constexpr double kStart = 1.0;

  /// Creates (or truncates) the bag; throws std::runtime_error naming the file if it cannot.
  BagWriter(const std::string& path, const SimConfig& config, RenderMode mode = RenderMode::Mesh,
            int strands_per_strip = 6);
  /// One output frame (frame.meshes must be set: run with RunOptions::build_meshes); body_frames are
  /// the world poses of the bodies' frames.
  void write(const OutputFrame& frame, const std::vector<Iso3>& body_frames);
  /// Closes the bag (the destructor does too).
  void close();
  long messagesWritten() const { return messages_; }

 private:
  rosbag::Bag bag_;
  std::string path_;
  SimConfig config_;
  RenderMode mode_;
  int strands_per_strip_;
  std::vector<Iso3> written_body_frames_;
  long messages_ = 0;
};

}  // namespace hair_sim
