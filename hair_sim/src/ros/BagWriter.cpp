#include "hair_sim/ros/BagWriter.hpp"

#include <ros/message_traits.h>
#include <tf2_msgs/TFMessage.h>

#include <boost/make_shared.hpp>
#include <stdexcept>

namespace hair_sim {

namespace {

/// A connection header like a latched publisher's, so that `rosbag play` latches the topic too.
template <typename M>
boost::shared_ptr<ros::M_string> latchedHeader() {
  auto header = boost::make_shared<ros::M_string>();
  (*header)["type"] = ros::message_traits::datatype<M>();
  (*header)["md5sum"] = ros::message_traits::md5sum<M>();
  (*header)["message_definition"] = ros::message_traits::definition<M>();
  (*header)["callerid"] = "/hair_sim_offline";
  (*header)["latching"] = "1";
  return header;
}

}  // namespace

BagWriter::BagWriter(const std::string& path, const SimConfig& config, RenderMode mode, int strands_per_strip)
    : path_(path), config_(config), mode_(mode), strands_per_strip_(strands_per_strip) {
  try {
    bag_.open(path, rosbag::bagmode::Write);
    bag_.setCompression(rosbag::compression::LZ4);
  } catch (const rosbag::BagException& e) {
    throw std::runtime_error(path + ": cannot write the bag: " + e.what());
  }
}

void BagWriter::write(const OutputFrame& frame, const std::vector<Iso3>& body_frames) {
  if (!frame.meshes) throw std::logic_error("BagWriter::write(...) : the frame has no meshes");
  const ros::Time stamp(kStart + frame.t);
  tf2_msgs::TFMessage tf;
  tf.transforms.push_back(makeTransform(frame.head_pose, config_.world_frame, config_.head_frame, stamp));
  bag_.write("/tf", stamp, tf);
  bag_.write("/hair_state", stamp,
             makeHairState(*frame.simulator, *frame.points_world, config_.world_frame, stamp));
  bag_.write("/hair_markers", stamp,
             makeHairMarkers(*frame.meshes, mode_, strands_per_strip_, config_.world_frame, stamp));
  messages_ += 3;
  bool moved = written_body_frames_.size() != body_frames.size();
  for (std::size_t b = 0; !moved && b < body_frames.size(); ++b)
    moved = (body_frames[b].matrix() - written_body_frames_[b].matrix()).cwiseAbs().maxCoeff() > 1e-6;
  if (moved) {
    static const auto header = latchedHeader<visualization_msgs::MarkerArray>();
    bag_.write("/collision_bodies", stamp,
               makeBodyMarkers(config_.bodies, body_frames, config_.head_frame, config_.world_frame, stamp),
               header);
    written_body_frames_ = body_frames;
    ++messages_;
  }
}

void BagWriter::close() { bag_.close(); }

}  // namespace hair_sim
