#include "hair_sim/ros/BagWriter.hpp"

#include <ros/message_traits.h>
#include <tf2_msgs/TFMessage.h>

#include <boost/make_shared.hpp>
#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <vector>

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

template <typename Action>
void BagWriter::guarded(const char* what, Action action) {
  if (!bag_) throw std::logic_error(path_ + ": the bag was abandoned after an earlier error");
  errno = 0;
  try {
    action();
  } catch (const rosbag::BagException& e) {
    const int err = errno;  // rosbag's messages give byte counts, not the reason
    abandon();
    throw std::runtime_error(path_ + ": " + what + ": " + e.what() +
                             (err != 0 ? std::string(" (") + std::strerror(err) + ")" : std::string()));
  }
}

void BagWriter::abandon() noexcept {
  if (!bag_) return;
  try {
    bag_->close();
    bag_.reset();
  } catch (...) {
    // close() failed half way (e.g. writing the index on a full disk): the bag stays "open" and
    // ~Bag() would call close() again, which throws from a destructor (std::terminate). Keep the handle
    // instead, never destroyed but reachable (so a leak checker does not report it); its memory and file
    // descriptor are released at exit.
    static std::vector<rosbag::Bag*>& abandoned = *new std::vector<rosbag::Bag*>();
    abandoned.push_back(bag_.release());
  }
}

BagWriter::BagWriter(const std::string& path, const SimConfig& config, RenderMode mode, int strands_per_strip)
    : bag_(std::make_unique<rosbag::Bag>()),
      path_(path),
      config_(config),
      mode_(mode),
      strands_per_strip_(strands_per_strip) {
  guarded("cannot write the bag", [this] {
    bag_->open(path_, rosbag::bagmode::Write);
    bag_->setCompression(rosbag::compression::LZ4);
  });
}

BagWriter::~BagWriter() { abandon(); }

void BagWriter::write(const OutputFrame& frame, const std::vector<Iso3>& body_frames) {
  if (!frame.meshes) throw std::logic_error("BagWriter::write(...) : the frame has no meshes");
  const ros::Time stamp(kStart + frame.t);
  tf2_msgs::TFMessage tf;
  tf.transforms.push_back(makeTransform(frame.head_pose, config_.world_frame, config_.head_frame, stamp));
  const auto state = makeHairState(*frame.simulator, *frame.points_world, config_.world_frame, stamp);
  const auto markers = makeHairMarkers(*frame.meshes, mode_, strands_per_strip_, config_.world_frame, stamp);
  guarded("cannot write the bag", [&] {
    bag_->write("/tf", stamp, tf);
    bag_->write("/hair_state", stamp, state);
    bag_->write("/hair_markers", stamp, markers);
  });
  messages_ += 3;
  bool moved = written_body_frames_.size() != body_frames.size();
  for (std::size_t b = 0; !moved && b < body_frames.size(); ++b)
    moved = (body_frames[b].matrix() - written_body_frames_[b].matrix()).cwiseAbs().maxCoeff() > 1e-6;
  if (moved) {
    static const auto header = latchedHeader<visualization_msgs::MarkerArray>();
    const auto bodies =
        makeBodyMarkers(config_.bodies, body_frames, config_.head_frame, config_.world_frame, stamp);
    guarded("cannot write the bag", [&] { bag_->write("/collision_bodies", stamp, bodies, header); });
    written_body_frames_ = body_frames;
    ++messages_;
  }
}

void BagWriter::close() {
  if (!bag_) return;  // abandoned: the error was reported when it happened
  guarded("cannot finish the bag (index and header)", [this] { bag_->close(); });
}

}  // namespace hair_sim
