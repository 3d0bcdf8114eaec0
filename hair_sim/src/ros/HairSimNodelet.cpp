/// hair_sim/HairSimNodelet: the node's class inside a nodelet manager, so that subscribers in the same
/// manager get hair_state and hair_markers without serialisation (the node publishes shared pointers).
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include <exception>
#include <memory>

#include "hair_sim/ros/HairSimNode.hpp"

namespace hair_sim {

class HairSimNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    // getNodeHandle()/getPrivateNodeHandle() share the nodelet's single-threaded queue: the node's
    // callbacks never run concurrently, as in hair_sim_node.
    try {
      node_ = std::make_unique<HairSimNode>(getNodeHandle(), getPrivateNodeHandle());
    } catch (const std::exception& e) {
      NODELET_FATAL("hair_sim: %s", e.what());
      throw;  // the manager reports the failed load
    }
  }

  std::unique_ptr<HairSimNode> node_;
};

}  // namespace hair_sim

PLUGINLIB_EXPORT_CLASS(hair_sim::HairSimNodelet, nodelet::Nodelet)
