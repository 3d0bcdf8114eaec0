#pragma once
/// ROS glue of hair_sim: parameters, the head pose through tf2, wind commands, the fixed-step loop,
/// markers and state out, the reset service. The physics lives in the ROS-free core.
#include <geometry_msgs/TransformStamped.h>
#include <hair_sim_msgs/HairEvent.h>
#include <hair_sim_msgs/Reset.h>
#include <hair_sim_msgs/Trigger.h>
#include <hair_sim_msgs/Wind.h>
#include <ros/ros.h>
#include <tf2_msgs/TFMessage.h>
#include <tf2_ros/buffer.h>
#include <visualization_msgs/MarkerArray.h>

#include <boost/shared_ptr.hpp>
#include <cstdint>

#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "hair_sim/core/Simulator.hpp"
#include "hair_sim/core/events/EventSchedule.hpp"
#include "hair_sim/core/events/WindCommand.hpp"
#include "hair_sim/core/geometry/HairMeshBuilder.hpp"
#include "hair_sim/core/model/SimConfig.hpp"
#include "hair_sim/ros/HairMessages.hpp"
#include "hair_sim/ros/HairSimDiagnostics.hpp"
#include "hair_sim/ros/LiveParameters.hpp"

namespace hair_sim {

class HairSimNode {
 public:
  /// Reads the parameters and the config file; throws std::invalid_argument naming the parameter or
  /// key and value when one is bad.
  HairSimNode(ros::NodeHandle nh, ros::NodeHandle private_nh);
  /// Events scheduled and not yet ended, at most (more are refused, named, until some have ended).
  static constexpr std::size_t kMaxScheduledEvents = 256;
  /// Turbulence events acting at one time, at most: each adds EventSchedule::kTurbulenceWaves plane waves
  /// to the wind of every segment at every substep (at the default 100 strips on the 2-core build machine,
  /// 0.19 ms per substep each: 4 took 1.0 ms of the 4.17 ms budget, 8 took 2.2 ms, and 256 of them, within
  /// kMaxScheduledEvents, slowed the hair to a quarter of real time and the outputs to 1-2 Hz).
  static constexpr std::size_t kMaxOverlappingTurbulence = 4;

 private:
  void readParameters();
  void rebuild(Hairstyle hairstyle);
  /// meshes_ for the simulator's hairstyle with mesh_options_ and threads_.
  void makeMeshBuilder();
  void onTimer(const ros::TimerEvent& event);
  /// /tf and /tf_static into the buffer (what tf2_ros::TransformListener does), then update(): the hair
  /// steps as soon as a new head pose is in, and is published then if an output is due.
  void onTf(const ros::MessageEvent<tf2_msgs::TFMessage const>& event, bool is_static);
  /// Steps to the newest head pose and publishes if due (from_tf) or always (the timer, which only
  /// acts while no tf has come in for 1.5 output periods).
  void update(bool from_tf);
  /// One substep to t: the head state, the body frames, the wind and the events at t.
  void stepTo(const ros::Time& t, const HeadState& head, const std::vector<Iso3>& body_frames);
  /// A warning about `what` (tf, wind, event): said at once when it differs from the last one about it,
  /// else at most every 2 s (a stream of the same bad input does not flood the log). With `every` > 0, at
  /// most every `every` s whatever the text (tf lookups, whose texts carry times).
  void warnThrottled(const std::string& what, const std::string& text, double every = 0.0);
  /// A subscriber connected to an output: with ~tcp_nodelay, TCP_NODELAY on the connections accepted on the
  /// node's TCPROS port (setTcpNoDelayOnAccepted), as roscpp does when a subscriber asks for it.
  void onSubscriberConnect();
  /// A transform of the head frame, of a body's frame or of a frame above either (map -> odom, say) that
  /// jumps beyond the teleport limits from the previous one of its child frame (for a frame above the head,
  /// the distance the head moves; for another frame with bodies in or below it, how far the farthest
  /// point of a body can move, bounded by its center's move plus the turn times its largest radius): the
  /// previous one is put in
  /// the buffer again just before it, so that the jump falls within one substep (a teleport of the head, or
  /// a body that jumps) instead of a sweep that tf would interpolate between the two messages. Said for any
  /// frame but the head's own (whose teleport the step reports).
  /// Whether a node besides this one (a head driver) subscribes to events, which head motions go to.
  bool headDriverSubscribed() const;
  void holdBeforeJump(const geometry_msgs::TransformStamped& t, const std::string& authority);
  /// Records `parent` as `child`'s parent frame (parent_frame_); when that is news, hair_frames_,
  /// above_head_ and bodies_below_ again.
  void noteParent(const std::string& child, const std::string& parent);
  /// Stamp order of a non-static transform against the newest one of its child frame: false (with a
  /// throttled warning naming frame and stamps) for a repeated stamp or one older than the tf cache, which
  /// tf2 would refuse with a TF_REPEATED_DATA or TF_OLD_DATA line on every message, or one further ahead of
  /// `now` (the clock at the message's arrival) than the cache; older stamps within the cache (out of order)
  /// are taken, counted and reported throttled.
  bool acceptTfStamp(const geometry_msgs::TransformStamped& t, const std::string& authority,
                     const ros::Time& now);
  void onWind(const hair_sim_msgs::Wind::ConstPtr& msg);
  bool onReset(hair_sim_msgs::Reset::Request& request, hair_sim_msgs::Reset::Response& response);
  void onEvent(const hair_sim_msgs::HairEvent::ConstPtr& msg);
  bool onTrigger(hair_sim_msgs::Trigger::Request& request, hair_sim_msgs::Trigger::Response& response);
  /// Schedules a wind, turbulence or gravity event (head motions: false, "for the head driver").
  /// Returns whether it was accepted; `message` says what was done or what was wrong.
  bool schedule(const hair_sim_msgs::HairEvent& msg, std::string* message);
  /// The one place that asks tf: pose of `frame` in world_frame at `stamp`; on failure warns at most
  /// every 5 s per frame (naming both frames and tf's reason) and returns false. stamp 0 = the newest;
  /// `found` receives the stamp of the transform used.
  bool lookupPose(const std::string& frame, const ros::Time& stamp, Iso3& pose, ros::Time* found = nullptr);
  /// Body b's frame at substep time t: from tf; else, when tf has nothing of it newer than max_tf_age (or
  /// nothing at all) and it was seen before, where it was last seen (said once, and when it is fresh again);
  /// false (wait) when it was never seen or is only behind the head.
  bool bodyFrameAt(std::size_t b, const ros::Time& t, Iso3& frame);
  /// hair_state and hair_markers: the hair drawn with the head at `pose`, bodies at `body_frames`.
  void publishOutputs(const ros::Time& stamp, const Iso3& pose, const std::vector<Iso3>& body_frames);
  void publishBodies(const ros::Time& stamp, const std::vector<Iso3>& frames);
  /// k * period as a ROS time, and the largest k with k * period <= t (long double: exact to the nanosecond).
  static ros::Time gridTime(int64_t k, double period);
  static int64_t gridIndexAtOrBefore(const ros::Time& t, double period);
  /// Moves the substep grid to its last point at or before t (a start or a skip ahead).
  void snapSimTime(const ros::Time& t);
  /// Takes the live settings (dynamic_reconfigure) changed since the last call, between two substeps.
  void applyLiveSettings();

  ros::NodeHandle nh_, pnh_;
  tf2_ros::Buffer tf_buffer_;
  ros::Subscriber tf_sub_, tf_static_sub_;
  ros::Time last_tf_receipt_;  ///< to clear the buffer when time jumps back, as tf2_ros does
  ros::Time
      next_publish_;  ///< when the next output is due: stamp of the head pose (a multiple of the period)
  ros::WallTime last_tf_update_;  ///< last update() on a tf arrival
  double tf_interval_ = 0.0;      ///< recent wall time between two of them (s, at most max_tf_age)
  ros::Subscriber wind_sub_, events_sub_;
  ros::Publisher markers_pub_, bodies_pub_, state_pub_, events_pub_;
  ros::ServiceServer reset_srv_, trigger_srv_;
  ros::Timer timer_;

  std::string config_file_;
  SimConfig config_;
  RenderMode render_mode_ = RenderMode::Mesh;
  HairMeshOptions mesh_options_;
  int max_substeps_per_update_ = 60;
  int threads_ = 1;          ///< Simulator::setThreads
  bool tcp_nodelay_ = true;  ///< TCP_NODELAY on the subscribers' connections (onSubscriberConnect)
  double max_tf_age_ = 0.5;  ///< s: a newer head pose than this is expected; older = stale
  bool head_stale_ = false;
  ros::Time newest_head_stamp_;  ///< stamp of the newest head pose at the last update (time going back)
  double teleport_distance_ = 0.5, teleport_angle_ = 1.0;  ///< m, rad (between two head tf messages)
  std::map<std::string, std::pair<ros::WallTime, std::string>> last_warning_;  ///< warnThrottled
  std::vector<bool> body_held_;  ///< per body: held at last_body_frames_ (bodyFrameAt)
  /// child frame -> the newest non-static transform received of it (holdBeforeJump)
  std::map<std::string, geometry_msgs::TransformStamped> last_tf_;
  std::map<std::string, std::string> parent_frame_;  ///< child frame -> parent, from the tf received
  /// The head frame, the bodies' frames and every frame above them in parent_frame_ (holdBeforeJump's)
  std::set<std::string> hair_frames_;
  std::set<std::string> above_head_;  ///< the frames above the head frame in parent_frame_ (noteParent's)
  /// frame -> the bodies (config_.bodies' indices) in it or below it in parent_frame_ (noteParent's)
  std::map<std::string, std::vector<std::size_t>> bodies_below_;
  std::map<std::string, ros::Time> newest_tf_stamp_;  ///< child frame -> newest stamp taken
  int strands_per_strip_ = 6;

  std::unique_ptr<Simulator> simulator_;
  std::unique_ptr<HairMeshBuilder> meshes_;
  std::int64_t min_triangles_ = 0;  ///< the hairstyle's triangles at the coarsest level (1 x 1)
  HeadMotionEstimator head_;
  bool started_ = false;
  /// The substeps lie on a grid fixed in ROS time, sim_time_ = gridTime(sim_step_) = sim_step_ * substep, so
  /// that a replay of the same tf (rosbag, use_sim_time) samples the head at the same instants as the live
  /// run.
  int64_t sim_step_ = 0;
  ros::Time sim_time_;
  std::vector<Iso3> last_body_frames_;
  std::vector<Iso3> published_body_frames_;
  std::vector<Vec3> world_points_;
  std::vector<Ellipsoid> bodies_scratch_;  ///< the bodies in the world frame for the mesh (publishOutputs)
  /// The last hair_state published; filled again in place when no subscriber in this process still holds it.
  boost::shared_ptr<hair_sim_msgs::HairState> state_msg_;
  /// hair_markers, serialised straight from meshes_ within publish().
  HairMarkersView markers_view_;

  // The Wind commands, timed in seconds of ROS time.
  WindCommand wind_;
  // Events (wind, wind_gust, turbulence, gravity), timed in seconds of ROS time.
  EventSchedule events_;

  // Status.
  ros::WallTime status_since_;
  long status_steps_ = 0;
  double status_step_seconds_ = 0.0;
  long status_publishes_ = 0;
  ros::WallTime tf_received_;  ///< arrival of the tf message being handled
  double status_tf_to_output_sum_ = 0.0, status_tf_to_output_max_ = 0.0;  ///< s, outputs made on a tf
  long status_tf_outputs_ = 0;

  // Live tuning and /diagnostics (LiveParameters.hpp, HairSimDiagnostics.hpp).
  double wind_scale_ = 1.0;
  std::unique_ptr<HairSimDiagnostics> diagnostics_;
  std::unique_ptr<LiveParameters> live_;
};

}  // namespace hair_sim
