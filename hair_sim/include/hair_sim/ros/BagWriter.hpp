#pragma once
/// Bakes an offline run into a rosbag that `rosbag play` and the shipped rviz config show as the node
/// would have published it: /tf (world_frame -> head_frame), /hair_markers, /collision_bodies
/// (latched, written when a body moved) and /hair_state, at bag time kStart + t.
#include <rosbag/bag.h>

#include <memory>
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
  /// Closes the bag if still open; never throws (a bag that cannot be closed is abandoned, see below).
  ~BagWriter();
  BagWriter(const BagWriter&) = delete;
  BagWriter& operator=(const BagWriter&) = delete;
  /// One output frame (frame.meshes must be set: run with RunOptions::build_meshes); body_frames are
  /// the world poses of the bodies' frames.
  ///
  /// Every rosbag error (a full disk, a file size limit) in the constructor, write() and close() becomes a
  /// std::runtime_error naming the bag's path, what failed and the reason. The bag is then abandoned: it
  /// is closed if rosbag can still close it, otherwise its handle is dropped (rosbag::Bag's destructor
  /// would retry the failing close() and throw from a destructor, i.e. std::terminate); its file is left
  /// as it is (incomplete) for the caller to remove, and a later write() throws std::logic_error.
  void write(const OutputFrame& frame, const std::vector<Iso3>& body_frames);
  /// Writes the index and closes the bag (the destructor does too, ignoring errors).
  void close();
  long messagesWritten() const { return messages_; }
  const std::string& path() const { return path_; }

 private:
  /// Runs action on the bag, turning a rosbag error into the std::runtime_error described above.
  template <typename Action>
  void guarded(const char* what, Action action);
  /// Closes the bag after an error, or drops it when even close() fails; never throws.
  void abandon() noexcept;

  std::unique_ptr<rosbag::Bag> bag_;
  std::string path_;
  SimConfig config_;
  RenderMode mode_;
  int strands_per_strip_;
  std::vector<Iso3> written_body_frames_;
  long messages_ = 0;
};

}  // namespace hair_sim
