#include "hair_sim/ros/HairSimNode.hpp"

#include <geometry_msgs/TransformStamped.h>
#include <ros/connection_manager.h>
#include <tf2_eigen/tf2_eigen.h>

#include <algorithm>
#include <boost/bind/bind.hpp>
#include <boost/make_shared.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <stdexcept>
#include <system_error>
#include <type_traits>

#include "hair_sim/core/model/HairstyleIO.hpp"
#include "hair_sim/core/util/YamlReader.hpp"
#include "hair_sim/ros/InputChecks.hpp"
#include "hair_sim/ros/TcpNoDelay.hpp"

namespace hair_sim {

namespace {

std::invalid_argument badParam(const std::string& name, const std::string& value, const std::string& rule) {
  return std::invalid_argument("parameter ~" + name + ": '" + value + "' " + rule);
}

/// Runs a callback's body: an exception (an input no check caught, or a bug) is logged with the callback
/// named, and the node goes on (roscpp does not catch what a callback throws: the node would end).
template <typename F>
void guarded(const char* callback, F body) {
  try {
    body();
  } catch (const std::exception& e) {
    ROS_ERROR_THROTTLE(5.0, "hair_sim: %s failed: %s; the node goes on", callback, e.what());
  }
}

const char* typeName(const std::string*) { return "a string"; }
const char* typeName(const int*) { return "an integer"; }
const char* typeName(const double*) { return "a number"; }
const char* typeName(const bool*) { return "true or false"; }

/// Private parameter `name` into `value` if it is set (returns whether it was); set with the wrong type
/// (e.g. _publish_rate:=fast), it stops the start with the parameter and the value named, rather than
/// being ignored.
template <typename T>
bool readParam(const ros::NodeHandle& nh, const std::string& name, T& value) {
  if (!nh.hasParam(name)) return false;
  XmlRpc::XmlRpcValue raw;
  nh.getParam(name, raw);
  // roscpp would round 2.5 to an integer 3: integers must be given as integers.
  const bool integer_wanted = std::is_same<T, int>::value;
  if (!(integer_wanted && raw.getType() != XmlRpc::XmlRpcValue::TypeInt) && nh.getParam(name, value))
    return true;
  std::string shown = raw.toXml();
  if (raw.getType() == XmlRpc::XmlRpcValue::TypeString) shown = static_cast<std::string>(raw);
  if (raw.getType() == XmlRpc::XmlRpcValue::TypeDouble) shown = formatDouble(static_cast<double>(raw));
  if (raw.getType() == XmlRpc::XmlRpcValue::TypeBoolean) shown = static_cast<bool>(raw) ? "true" : "false";
  throw badParam(name, shown, std::string("must be ") + typeName(&value));
}

}  // namespace

HairSimNode::HairSimNode(ros::NodeHandle nh, ros::NodeHandle private_nh) : nh_(nh), pnh_(private_nh) {
  readParameters();
  body_held_.assign(config_.bodies.size(), false);
  Hairstyle style = loadHairstyle(config_.hairstyle_file);
  // A triangle budget below the coarsest level cannot be met (the core refuses it): name the parameter.
  min_triangles_ = HairMeshBuilder::minimumTriangles(style);
  if (mesh_options_.max_triangles > 0 && mesh_options_.max_triangles < min_triangles_)
    throw badParam("max_triangles", std::to_string(mesh_options_.max_triangles),
                   "is below the coarsest level's " + std::to_string(min_triangles_) +
                       " triangles (1 x 1) for this hairstyle: at least that, or 0 (off)");
  rebuild(std::move(style));
  // Before any subscription: in a nodelet manager callbacks may start as soon as they exist.
  diagnostics_ = std::make_unique<HairSimDiagnostics>(
      nh_, pnh_, pnh_.getNamespace(), "hair_sim " + config_.head_frame, config_.physics.substep);
  LiveSettings live;
  live.physics = config_.physics;
  live.wind_scale = wind_scale_;
  live.render_mode = render_mode_ == RenderMode::Mesh      ? "mesh"
                     : render_mode_ == RenderMode::Strands ? "strands"
                                                           : "both";
  live.mesh = mesh_options_;
  live_ = std::make_unique<LiveParameters>(pnh_, live, min_triangles_);
  // A subscriber that connects gets TCP_NODELAY on its connection (~tcp_nodelay), whether it asked or not.
  const ros::SubscriberStatusCallback connected = boost::bind(&HairSimNode::onSubscriberConnect, this);
  markers_pub_ = nh_.advertise<visualization_msgs::MarkerArray>("hair_markers", 2, connected);
  bodies_pub_ = nh_.advertise<visualization_msgs::MarkerArray>(
      "collision_bodies", 1, connected, ros::SubscriberStatusCallback(), ros::VoidConstPtr(), true);
  state_pub_ = nh_.advertise<hair_sim_msgs::HairState>("hair_state", 2, connected);
  wind_sub_ = nh_.subscribe("wind", 10, &HairSimNode::onWind, this);
  events_pub_ = nh_.advertise<hair_sim_msgs::HairEvent>("events", 10);
  // A burst of events (a scenario sent at once) waits in the queue rather than being dropped unseen by
  // roscpp while an update runs: room for the cap and its refusals (each named) several times over.
  events_sub_ = nh_.subscribe("events", 4 * kMaxScheduledEvents, &HairSimNode::onEvent, this);
  reset_srv_ = nh_.advertiseService("reset", &HairSimNode::onReset, this);
  trigger_srv_ = nh_.advertiseService("trigger", &HairSimNode::onTrigger, this);
  // tf on the node's own queue (no listener thread): a head pose triggers the step and the output.
  tf_sub_ = nh_.subscribe<tf2_msgs::TFMessage>(
      "/tf", 100, boost::bind(&HairSimNode::onTf, this, boost::placeholders::_1, false), ros::VoidConstPtr(),
      ros::TransportHints().tcpNoDelay());
  tf_static_sub_ = nh_.subscribe<tf2_msgs::TFMessage>(
      "/tf_static", 100, boost::bind(&HairSimNode::onTf, this, boost::placeholders::_1, true));
  timer_ = nh_.createTimer(ros::Duration(1.0 / config_.publish_rate), &HairSimNode::onTimer, this);
  status_since_ = ros::WallTime::now();
  ROS_INFO(
      "hair_sim: %zu strips, %d control points, %zu bodies, substep %.5f s, publishing at %.1f Hz in '%s', "
      "head frame '%s', level of detail %d x %d, %d step thread%s",
      simulator_->hairstyle().strips.size(), simulator_->controlPointCount(), config_.bodies.size(),
      config_.physics.substep, config_.publish_rate, config_.world_frame.c_str(), config_.head_frame.c_str(),
      meshes_->levelOfDetail().samples_across, meshes_->levelOfDetail().samples_along, simulator_->threads(),
      simulator_->threads() == 1 ? "" : "s");
}

void HairSimNode::readParameters() {
  if (!readParam(pnh_, "config_file", config_file_) || config_file_.empty())
    throw badParam("config_file", config_file_, "is required: the path of config/hair_sim.yaml");
  std::error_code no_file;
  if (config_file_.front() != '/' && !std::filesystem::exists(config_file_, no_file)) {
    // roslaunch reads a relative path from the shell's directory, the node from its own (ROS_HOME).
    throw badParam("config_file", config_file_,
                   "is a relative path, and there is no such file in the node's working directory " +
                       std::filesystem::current_path(no_file).string() +
                       " (roslaunch runs nodes in ROS_HOME): give an absolute path, e.g. config:=$(pwd)/" +
                       config_file_);
  }
  config_ = loadSimConfig(config_file_);  // names file, key, line and value on error
  const std::string file_world_frame = config_.world_frame, file_head_frame = config_.head_frame;
  // Individual parameters override the file (launch file arguments).
  std::string frame;
  if (readParam(pnh_, "world_frame", frame)) {
    if (!isValidFrameName(frame)) throw badParam("world_frame", frame, "is not a valid tf frame name");
    config_.world_frame = frame;
  }
  if (readParam(pnh_, "head_frame", frame)) {
    if (!isValidFrameName(frame)) throw badParam("head_frame", frame, "is not a valid tf frame name");
    config_.head_frame = frame;
  }
  if (config_.world_frame == config_.head_frame)
    throw badParam("head_frame", config_.head_frame, "must differ from world_frame");
  // Bodies fixed in the file's world or head frame follow the overrides: one file serves several avatars.
  for (Body& body : config_.bodies) {
    if (body.frame == file_world_frame)
      body.frame = config_.world_frame;
    else if (body.frame == file_head_frame)
      body.frame = config_.head_frame;
  }
  double rate = 0.0;
  if (readParam(pnh_, "publish_rate", rate)) {
    if (!(std::isfinite(rate) && rate > 0.0 && rate <= 1.0 / config_.physics.substep))
      throw badParam("publish_rate", formatDouble(rate), "must be in (0, 1/substep] Hz");
    config_.publish_rate = rate;
  }
  std::string mode = "mesh";
  readParam(pnh_, "render_mode", mode);
  if (!parseRenderMode(mode, &render_mode_))
    throw badParam("render_mode", mode, "must be mesh, strands or both");
  int across = 2, along = 4, max_triangles = 0;
  readParam(pnh_, "samples_across", across);
  readParam(pnh_, "samples_along", along);
  readParam(pnh_, "max_triangles", max_triangles);
  if (across < 1 || across > 64) throw badParam("samples_across", std::to_string(across), "must be in 1..64");
  if (along < 1 || along > 64) throw badParam("samples_along", std::to_string(along), "must be in 1..64");
  if (max_triangles < 0)
    throw badParam("max_triangles", std::to_string(max_triangles), "must be >= 0 (0 = off)");
  mesh_options_.level_of_detail = LevelOfDetail{across, along};
  mesh_options_.max_triangles = max_triangles;
  readParam(pnh_, "max_substeps_per_update", max_substeps_per_update_);
  if (max_substeps_per_update_ < 1 || max_substeps_per_update_ > 24000)
    throw badParam("max_substeps_per_update", std::to_string(max_substeps_per_update_),
                   "must be in 1..24000 (100 s of substeps at 240 Hz)");
  double smoothing = 0.02;
  readParam(pnh_, "head_smoothing", smoothing);
  if (!(std::isfinite(smoothing) && smoothing >= 0.0 && smoothing <= 1.0))
    throw badParam("head_smoothing", formatDouble(smoothing), "must be in [0, 1] s");
  head_ = HeadMotionEstimator(smoothing);
  double teleport_distance = 0.5, teleport_angle = 1.0;
  readParam(pnh_, "teleport_distance", teleport_distance);
  readParam(pnh_, "teleport_angle", teleport_angle);
  if (!(std::isfinite(teleport_distance) && teleport_distance > 0.0))
    throw badParam("teleport_distance", formatDouble(teleport_distance), "must be > 0 m");
  if (!(std::isfinite(teleport_angle) && teleport_angle > 0.0))
    throw badParam("teleport_angle", formatDouble(teleport_angle), "must be > 0 rad");
  head_.setTeleportLimits(teleport_distance, teleport_angle);
  teleport_distance_ = teleport_distance;
  teleport_angle_ = teleport_angle;
  readParam(pnh_, "max_tf_age", max_tf_age_);
  if (!(std::isfinite(max_tf_age_) && max_tf_age_ > 0.0 && max_tf_age_ <= 5.0))
    throw badParam("max_tf_age", formatDouble(max_tf_age_), "must be in (0, 5] s (the tf cache holds 10 s)");
  readParam(pnh_, "threads", threads_);
  if (threads_ < 1 || threads_ > 64) throw badParam("threads", std::to_string(threads_), "must be in 1..64");
  readParam(pnh_, "strands_per_strip", strands_per_strip_);
  if (strands_per_strip_ < 1 || strands_per_strip_ > 10000)
    throw badParam("strands_per_strip", std::to_string(strands_per_strip_), "must be in 1..10000");
  readParam(pnh_, "tcp_nodelay", tcp_nodelay_);
  readParam(pnh_, "wind_scale", wind_scale_);
  if (!(std::isfinite(wind_scale_) && wind_scale_ >= 0.0 && wind_scale_ <= 100.0))
    throw badParam("wind_scale", formatDouble(wind_scale_), "must be in [0, 100]");
}

void HairSimNode::rebuild(Hairstyle hairstyle) {
  simulator_ = std::make_unique<Simulator>(std::move(hairstyle), config_.physics, config_.bodies);
  simulator_->setThreads(threads_);
  makeMeshBuilder();
}

void HairSimNode::makeMeshBuilder() {
  meshes_ = std::make_unique<HairMeshBuilder>(simulator_->hairstyle(), mesh_options_);
  meshes_->setThreads(threads_);
}

bool HairSimNode::lookupPose(const std::string& frame, const ros::Time& stamp, Iso3& pose, ros::Time* found) {
  if (frame == config_.world_frame) {
    pose = Iso3::Identity();
    if (found) *found = stamp;
    return true;
  }
  try {
    const geometry_msgs::TransformStamped t =
        // Without a timeout: tf2_ros::Buffer's timeout overload logs an error on every call when no
        // dedicated thread fills the buffer (this node fills it itself, in onTf).
        tf_buffer_.lookupTransform(config_.world_frame, frame, stamp);
    pose = tf2::transformToEigen(t);
    if (found) *found = t.header.stamp;
    if (!pose.matrix().allFinite()) {
      warnThrottled("lookup " + frame,
                    "hair_sim: tf " + config_.world_frame + " -> " + frame +
                        " has non-finite values; holding the last good pose",
                    5.0);
      return false;
    }
    return true;
  } catch (const tf2::TransformException& e) {
    char at[32];
    std::snprintf(at, sizeof(at), "%.3f", stamp.toSec());
    // At most every 5 s per frame: one frame's failures, at every substep, do not hide another's.
    warnThrottled("lookup " + frame,
                  "hair_sim: no tf " + config_.world_frame + " -> " + frame + " at " + at + ": " + e.what(),
                  5.0);
    return false;
  }
}

bool HairSimNode::bodyFrameAt(std::size_t b, const ros::Time& t, Iso3& frame) {
  const Body& body = config_.bodies[b];
  if (lookupPose(body.frame, t, frame)) {
    if (body_held_[b])
      ROS_INFO("hair_sim: body '%s': tf %s -> %s fresh again", body.name.c_str(), config_.world_frame.c_str(),
               body.frame.c_str());
    body_held_[b] = false;
    return true;
  }
  if (b >= last_body_frames_.size()) return false;  // never seen: wait for it
  // Only behind the head (a slower source): wait for it. Stale (nothing newer than max_tf_age, or gone):
  // held where it was last seen, as a stale head is, so that the hair goes on.
  Iso3 newest;
  ros::Time stamp;
  const double age = lookupPose(body.frame, ros::Time(0), newest, &stamp)
                         ? ros::Time::now().toSec() - stamp.toSec()
                         : std::numeric_limits<double>::infinity();
  if (age <= max_tf_age_) return false;
  if (!body_held_[b]) {
    ROS_WARN(
        "hair_sim: body '%s': no tf %s -> %s newer than max_tf_age (%.2f s): held where it was last seen",
        body.name.c_str(), config_.world_frame.c_str(), body.frame.c_str(), max_tf_age_);
    diagnostics_->droppedInput("body " + body.name + ": tf stale, held");
    body_held_[b] = true;
  }
  frame = last_body_frames_[b];
  return true;
}

void HairSimNode::onWind(const hair_sim_msgs::Wind::ConstPtr& msg) {
  guarded("the Wind callback", [&] {
    const std::string problem = checkWind(*msg);
    if (!problem.empty()) {
      warnThrottled("wind", "hair_sim: ignored a Wind message: " + problem + "; the last good wind holds");
      diagnostics_->droppedInput("wind: " + problem);
      return;
    }
    const Vec3 v(msg->velocity.x, msg->velocity.y, msg->velocity.z);
    Vec3 world = v;
    const std::string frame = msg->header.frame_id;
    if (!frame.empty() && frame != config_.world_frame) {
      Iso3 pose;
      if (!lookupPose(frame, ros::Time(0), pose)) {
        warnThrottled("wind", "hair_sim: ignored a Wind message: header.frame_id '" + frame +
                                  "' is unknown (no tf to '" + config_.world_frame +
                                  "'); the last good wind holds");
        diagnostics_->droppedInput("wind: no tf from '" + frame + "'");
        return;
      }
      world = pose.linear() * v;
    }
    // The ramp starts at header.stamp (so that a replay starts it at the same instant of the hair's time),
    // or on arrival when the stamp is zero or further than max_tf_age from the clock.
    // (Differences of stamps in double: ros::Duration throws beyond 68 years.)
    const double now = ros::Time::now().toSec();
    double start = started_ ? sim_time_.toSec() : now;
    if (!msg->header.stamp.isZero() && std::abs(msg->header.stamp.toSec() - now) <= max_tf_age_)
      start = msg->header.stamp.toSec();
    wind_.set(start, world, msg->turbulence, msg->ramp_time);
  });
}

bool HairSimNode::schedule(const hair_sim_msgs::HairEvent& msg, std::string* message) {
  EventType type;
  if (parseEventType(msg.type, &type) && isHeadMotion(type)) {
    *message = "a " + msg.type + " event is for the head driver";
    return false;
  }
  const Vec3 v(msg.vector.x, msg.vector.y, msg.vector.z);
  Vec3 world = v;
  const std::string& frame = msg.header.frame_id;
  if (!frame.empty() && frame != config_.world_frame && v.allFinite()) {
    Iso3 pose;
    if (!lookupPose(frame, ros::Time(0), pose)) {
      *message = "header.frame_id: no tf from '" + frame + "' to '" + config_.world_frame + "'";
      return false;
    }
    world = pose.linear() * v;
  }
  const ros::Time start = msg.header.stamp.isZero() ? ros::Time::now() : msg.header.stamp;
  Event event;
  std::string problem;
  if (!eventFromMsg(msg, world, start.toSec(), &event, &problem)) {
    *message = problem;
    return false;
  }
  // A bounded schedule: every substep weighs each event against the later ones of its type.
  if (events_.size() >= kMaxScheduledEvents) {
    *message = "too many events scheduled (" + std::to_string(events_.size()) + ", at most " +
               std::to_string(kMaxScheduledEvents) + "): wait until some have ended";
    return false;
  }
  if (event.type == EventType::Turbulence) {
    const std::size_t overlapping = events_.countOverlapping(event);
    if (overlapping >= kMaxOverlappingTurbulence) {
      *message = "too many turbulence events at once (" + std::to_string(overlapping) +
                 " scheduled would act while it does, at most " + std::to_string(kMaxOverlappingTurbulence) +
                 " together: each adds " + std::to_string(EventSchedule::kTurbulenceWaves) +
                 " plane waves to every segment's wind at every substep)";
      return false;
    }
  }
  // Over before the hair's time gets to it (its duration past, or, until replaced, replaced by a later
  // event of its type already scheduled): it would be dropped unseen at the next update.
  const double now = started_ ? sim_time_.toSec() : ros::Time::now().toSec();
  const double end = events_.endIfAdded(event);
  if (end < now) {
    *message = "header.stamp: " + formatDouble(event.start) + " s " +
               (event.duration > 0.0 ? "+ duration " + formatDouble(event.duration) + " s ended"
                                     : "until replaced: replaced by a later " + msg.type +
                                           " event by t = " + formatDouble(end) + " s,") +
               " before it arrived (t = " + formatDouble(now) + " s)";
    return false;
  }
  events_.add(event);
  *message = "scheduled " + msg.type + " at t = " + formatDouble(start.toSec()) + " s" +
             (event.duration > 0.0 ? " for " + formatDouble(event.duration) + " s" : " until replaced");
  return true;
}

void HairSimNode::onEvent(const hair_sim_msgs::HairEvent::ConstPtr& msg) {
  guarded("the HairEvent callback", [&] {
    std::string message;
    if (schedule(*msg, &message)) {
      ROS_INFO("hair_sim: event: %s", message.c_str());
      return;
    }
    EventType type;
    if (parseEventType(msg->type, &type) && isHeadMotion(type)) {  // the head driver's
      if (!headDriverSubscribed())
        warnThrottled("event", "hair_sim: a " + msg->type + " HairEvent on " + events_sub_.getTopic() +
                                   ": no head driver subscribes to it: nothing will move the head");
      return;
    }
    warnThrottled("event", "hair_sim: ignored a HairEvent (" + msg->type + "): " + message);
  });
}

bool HairSimNode::onTrigger(hair_sim_msgs::Trigger::Request& request,
                            hair_sim_msgs::Trigger::Response& response) {
  // Accepted (scheduled here, or passed on to the head driver), else the reason.
  auto take = [&](std::string* message) {
    EventType type;
    if (!(parseEventType(request.event.type, &type) && isHeadMotion(type)))
      return schedule(request.event, message);
    // Checked here so that the caller hears about a bad value; the head driver schedules it.
    Event event;
    const ros::Time start =
        request.event.header.stamp.isZero() ? ros::Time::now() : request.event.header.stamp;
    if (!eventFromMsg(request.event, Vec3::Zero(), start.toSec(), &event, message)) return false;
    if (!headDriverSubscribed()) {
      *message = "no head driver subscribes to " + events_pub_.getTopic() +
                 ": nothing would move the head (" + request.event.type +
                 " is a head motion; start head_driver, or move the head frame in tf)";
      return false;
    }
    hair_sim_msgs::HairEvent forward = request.event;
    forward.header.stamp = start;
    events_pub_.publish(forward);
    *message = "passed on to the head driver on " + events_pub_.getTopic() +
               " (starts at t = " + formatDouble(start.toSec()) + " s)";
    return true;
  };
  response.accepted = take(&response.message);
  if (response.accepted)
    ROS_INFO("hair_sim: trigger: %s", response.message.c_str());
  else
    warnThrottled("event",
                  "hair_sim: trigger refused a HairEvent (" + request.event.type + "): " + response.message);
  return true;
}

bool HairSimNode::headDriverSubscribed() const {
  return events_pub_.getNumSubscribers() >= 2;  // this node's own subscription to the topic counts as one
}

bool HairSimNode::onReset(hair_sim_msgs::Reset::Request& request, hair_sim_msgs::Reset::Response& response) {
  if (request.mode == hair_sim_msgs::Reset::Request::REST_POSE) {
    simulator_->reset();
    response.message = "back to the styled rest shape";
  } else if (request.mode == hair_sim_msgs::Reset::Request::KEEP_SHAPE) {
    Hairstyle style = simulator_->hairstyle();
    const std::vector<Vec3>& x = simulator_->positionsHead();
    const std::vector<int>& offsets = simulator_->stripOffsets();
    for (std::size_t s = 0; s < style.strips.size(); ++s)
      for (int p = 0; p < style.strips[s].pointCount(); ++p)
        style.strips[s].points[static_cast<std::size_t>(p)] = x[static_cast<std::size_t>(offsets[s] + p)];
    try {
      rebuild(std::move(style));
    } catch (const std::exception& e) {
      response.success = false;
      response.message = std::string("cannot keep the current shape: ") + e.what();
      return true;
    }
    response.message = "the current shape is the new rest shape";
  } else {
    response.success = false;
    response.message = "unknown mode " + std::to_string(request.mode) + " (0 = REST_POSE, 1 = KEEP_SHAPE)";
    return true;
  }
  response.success = true;
  ROS_INFO("hair_sim: reset: %s", response.message.c_str());
  return true;
}

void HairSimNode::onTf(const ros::MessageEvent<tf2_msgs::TFMessage const>& event, bool is_static) {
  guarded("the tf callback", [&] {
    tf_received_ = ros::WallTime::now();
    const ros::Time now = ros::Time::now();
    if (!is_static) {
      if (now < last_tf_receipt_) {
        ROS_WARN("hair_sim: time jumped back %.3f s: clearing the tf buffer",
                 (last_tf_receipt_ - now).toSec());
        tf_buffer_.clear();
        newest_tf_stamp_.clear();
        last_tf_.clear();
      }
      last_tf_receipt_ = now;
    }
    const std::string& authority = event.getPublisherName();
    ros::Time newest;  // newest stamp taken from this message
    for (const geometry_msgs::TransformStamped& t : event.getMessage()->transforms) {
      // A bad transform never enters the buffer (lookups would interpolate with it): the last good
      // one holds. A non-unit quaternion is normalised (tf2 would refuse it).
      geometry_msgs::TransformStamped fixed;
      bool normalised = false;
      const std::string problem = checkTransform(t, &fixed, &normalised);
      if (!problem.empty()) {
        warnThrottled("tf", "hair_sim: ignored tf " + t.header.frame_id + " -> " + t.child_frame_id +
                                " from " + authority + ": transform." + problem +
                                "; the last good pose holds");
        diagnostics_->droppedInput("tf " + t.child_frame_id + ": transform." + problem);
        continue;
      }
      if (normalised)
        ROS_WARN_THROTTLE(5.0, "hair_sim: tf %s -> %s from %s: rotation quaternion of norm %.6g normalised",
                          t.header.frame_id.c_str(), t.child_frame_id.c_str(), authority.c_str(),
                          std::sqrt(t.transform.rotation.x * t.transform.rotation.x +
                                    t.transform.rotation.y * t.transform.rotation.y +
                                    t.transform.rotation.z * t.transform.rotation.z +
                                    t.transform.rotation.w * t.transform.rotation.w));
      if (!is_static && !acceptTfStamp(fixed, authority, now)) continue;
      noteParent(fixed.child_frame_id, fixed.header.frame_id);
      if (!is_static && hair_frames_.count(fixed.child_frame_id) != 0) holdBeforeJump(fixed, authority);
      if (fixed.header.stamp > newest) newest = fixed.header.stamp;
      try {
        tf_buffer_.setTransform(fixed, authority, is_static);
        if (!is_static) {
          ros::Time& newest_of_child = newest_tf_stamp_[fixed.child_frame_id];
          if (fixed.header.stamp > newest_of_child) newest_of_child = fixed.header.stamp;
        }
      } catch (const tf2::TransformException& e) {
        ROS_WARN_THROTTLE(5.0, "hair_sim: tf %s -> %s from %s rejected: %s", t.header.frame_id.c_str(),
                          t.child_frame_id.c_str(), authority.c_str(), e.what());
      }
    }
    if (is_static || newest.isZero()) return;
    // Poses older than max_tf_age on arrival (the queue's backlog after the process stalled, or a late
    // source) are buffered without stepping and publishing for each: the next fresh one steps through them
    // all (within max_substeps_per_update), and the timer keeps the outputs going meanwhile.
    const double late = now.toSec() - newest.toSec();
    if (late > max_tf_age_) {
      ROS_WARN_THROTTLE(5.0,
                        "hair_sim: tf from %s is %.3f s old on arrival (max_tf_age %.2f s): buffered without "
                        "stepping (a backlog after a stall, or a late source)",
                        authority.c_str(), late, max_tf_age_);
      return;
    }
    update(true);
  });
}

void HairSimNode::noteParent(const std::string& child, const std::string& parent) {
  const auto known = parent_frame_.find(child);
  if (known != parent_frame_.end() && known->second == parent) return;
  parent_frame_[child] = parent;
  hair_frames_.clear();
  auto climb = [&](std::string frame) {
    while (hair_frames_.insert(frame).second) {  // stops at a frame already in (a loop in the tree, too)
      const auto up = parent_frame_.find(frame);
      if (up == parent_frame_.end()) return;
      frame = up->second;
    }
  };
  climb(config_.head_frame);
  above_head_ = hair_frames_;  // the head's climb alone
  above_head_.erase(config_.head_frame);
  for (const Body& body : config_.bodies) climb(body.frame);
  bodies_below_.clear();
  for (std::size_t b = 0; b < config_.bodies.size(); ++b) {
    std::set<std::string> seen;  // a loop in the tree ends the climb
    for (std::string frame = config_.bodies[b].frame; seen.insert(frame).second;) {
      bodies_below_[frame].push_back(b);
      const auto up = parent_frame_.find(frame);
      if (up == parent_frame_.end()) break;
      frame = up->second;
    }
  }
}

void HairSimNode::holdBeforeJump(const geometry_msgs::TransformStamped& t, const std::string& authority) {
  geometry_msgs::TransformStamped& last = last_tf_[t.child_frame_id];
  const geometry_msgs::TransformStamped previous = last;
  if (!(t.header.stamp > previous.header.stamp)) return;  // out of order: the newest one stays the reference
  last = t;
  if (previous.header.frame_id != t.header.frame_id) return;
  const Iso3 a = tf2::transformToEigen(previous), b = tf2::transformToEigen(t);
  if (a.matrix() == b.matrix()) return;  // not moved (a fixed frame sent again): no lookup below
  // For a frame above the head, how far the head moves: a turn moves it more than the frame's origin (a yaw
  // of 0.6 rad moves a head 1 m from the axis by 0.59 m). The head turns by the frame's own angle.
  Vec3 at = Vec3::Zero();  // the head's origin in the jumping frame, else the frame's own origin
  const bool above_head = above_head_.count(t.child_frame_id) != 0;
  if (above_head) {
    try {
      at = tf2::transformToEigen(
               tf_buffer_.lookupTransform(t.child_frame_id, config_.head_frame, ros::Time(0)))
               .translation();
    } catch (const tf2::TransformException&) {  // the head not yet in tf: the frame's origin
    }
  }
  double distance = (b * at - a * at).norm();
  const double angle = Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle();
  // For another frame with bodies in or below it (not the head's, nor one above it: there the hold must
  // agree with the head's teleport test, made at the head's origin), how far a body's surface can move: its
  // center's move plus the chord the turn gives its largest radius. A turn under teleport_angle may sweep a
  // large or distant body more than teleport_distance.
  std::string where = above_head ? " at the head" : "";
  const auto bodies = bodies_below_.find(t.child_frame_id);
  if (!above_head && t.child_frame_id != config_.head_frame && bodies != bodies_below_.end()) {
    for (const std::size_t i : bodies->second) {
      const Body& body = config_.bodies[i];
      Iso3 body_in_frame = Iso3::Identity();
      if (body.frame != t.child_frame_id) {
        try {
          body_in_frame =
              tf2::transformToEigen(tf_buffer_.lookupTransform(t.child_frame_id, body.frame, ros::Time(0)));
        } catch (const tf2::TransformException&) {  // not yet in tf: this body is not measured
          continue;
        }
      }
      const Vec3 center = body_in_frame * body.shape.center();
      const double reach =
          (b * center - a * center).norm() + 2.0 * std::sin(0.5 * angle) * body.shape.radii().maxCoeff();
      if (reach >= distance) {  // (a pure shift moves the body as far as the origin: said at the body)
        distance = reach;
        where = " at body '" + body.name + "'";
      }
    }
  }
  if (distance <= teleport_distance_ && angle <= teleport_angle_) return;
  // tf would interpolate the jump over the time between the two messages, a whip of the hair across the
  // scene; held at the old pose until just before the new one, the frame jumps within one substep. For
  // the head (its own frame or one above it) the head motion estimator takes that as a teleport: the hair
  // goes with the head rigidly, and the step says so.
  geometry_msgs::TransformStamped hold = previous;
  hold.header.stamp = t.header.stamp - ros::Duration(1e-6);
  if (!(hold.header.stamp > previous.header.stamp)) return;
  try {
    tf_buffer_.setTransform(hold, authority, false);
  } catch (const tf2::TransformException&) {
    return;
  }
  if (t.child_frame_id == config_.head_frame) return;
  char text[512];
  std::snprintf(text, sizeof(text),
                "hair_sim: tf %s -> %s from %s jumped %.3f m%s and %.3f rad between two messages "
                "(teleport_distance %.3f m, teleport_angle %.3f rad): held until the new one, so the frames "
                "below it jump within one substep",
                t.header.frame_id.c_str(), t.child_frame_id.c_str(), authority.c_str(), distance,
                where.c_str(), angle, teleport_distance_, teleport_angle_);
  warnThrottled("jump of " + t.child_frame_id, text);
}

bool HairSimNode::acceptTfStamp(const geometry_msgs::TransformStamped& t, const std::string& authority,
                                const ros::Time& now) {
  const auto known = newest_tf_stamp_.find(t.child_frame_id);
  const ros::Time newest = known == newest_tf_stamp_.end() ? ros::Time() : known->second;
  const ros::Time& stamp = t.header.stamp;
  const double cache = tf_buffer_.getCacheLength().toSec();
  if (stamp.isZero()) {
    ROS_WARN_THROTTLE(5.0, "hair_sim: ignored tf %s -> %s from %s: header.stamp is 0 (not on /tf_static)",
                      t.header.frame_id.c_str(), t.child_frame_id.c_str(), authority.c_str());
    diagnostics_->droppedInput("tf " + t.child_frame_id + ": header.stamp is 0");
    return false;
  }
  // Ahead of the clock by more than the cache (a wrong clock, a bad stamp): taken, it would hold the frame's
  // later transforms back as out of date until the clock caught up. (Not while the clock is 0: use_sim_time
  // before the first /clock.)
  const double ahead = stamp.toSec() - now.toSec();
  if (!now.isZero() && ahead > cache) {
    ROS_WARN_THROTTLE(5.0,
                      "hair_sim: ignored tf %s -> %s from %s: header.stamp %.6f is %.3f s ahead of the clock "
                      "(%.6f), beyond the %.1f s tf cache",
                      t.header.frame_id.c_str(), t.child_frame_id.c_str(), authority.c_str(), stamp.toSec(),
                      ahead, now.toSec(), cache);
    diagnostics_->droppedInput("tf " + t.child_frame_id + ": header.stamp ahead of the clock");
    return false;
  }
  if (stamp > newest) return true;  // (its child's newest once tf2 takes it, in onTf)
  const double behind = newest.toSec() - stamp.toSec();
  if (stamp == newest) {
    ROS_WARN_THROTTLE(5.0,
                      "hair_sim: ignored tf %s -> %s from %s: header.stamp %.6f repeats the previous one",
                      t.header.frame_id.c_str(), t.child_frame_id.c_str(), authority.c_str(), stamp.toSec());
    diagnostics_->droppedInput("tf " + t.child_frame_id + ": repeated header.stamp");
    return false;
  }
  if (behind >= cache) {
    ROS_WARN_THROTTLE(
        5.0,
        "hair_sim: ignored tf %s -> %s from %s: header.stamp %.6f is %.3f s older than the newest "
        "(%.6f), beyond the %.1f s tf cache",
        t.header.frame_id.c_str(), t.child_frame_id.c_str(), authority.c_str(), stamp.toSec(), behind,
        newest.toSec(), cache);
    diagnostics_->droppedInput("tf " + t.child_frame_id + ": header.stamp older than the tf cache");
    return false;
  }
  ROS_WARN_THROTTLE(
      5.0,
      "hair_sim: tf %s -> %s from %s arrived out of order: header.stamp %.6f is %.3f s older than "
      "the newest (%.6f); taken into the buffer",
      t.header.frame_id.c_str(), t.child_frame_id.c_str(), authority.c_str(), stamp.toSec(), behind,
      newest.toSec());
  return true;
}

void HairSimNode::stepTo(const ros::Time& t, const HeadState& head, const std::vector<Iso3>& body_frames) {
  StepInputs in;
  in.head = head;
  EventSample events = events_.sample(t.toSec(), config_.physics.gravity);
  in.wind = wind_scale_ * (wind_.at(t.toSec()) + events.wind);
  if (wind_scale_ != 1.0) events.turbulence.scale(wind_scale_);  // all the wind, turbulence events too
  in.turbulence = &events.turbulence;
  in.gravity = &events.gravity;
  in.body_frames = body_frames;
  simulator_->step(in);
}

void HairSimNode::onSubscriberConnect() {
  if (!tcp_nodelay_) return;
  // (In a nodelet manager: every connection accepted on the manager's TCPROS port, as one process.)
  const NoDelayResult r = setTcpNoDelayOnAccepted(ros::ConnectionManager::instance()->getTCPPort());
  if (!r.listed)
    warnThrottled(
        "tcp_nodelay",
        "hair_sim: ~tcp_nodelay: cannot list this process's sockets (/proc/self/fd): subscribers that "
        "do not ask for TCP_NODELAY keep Nagle's algorithm");
  else if (r.failed > 0)
    warnThrottled("tcp_nodelay", "hair_sim: ~tcp_nodelay: TCP_NODELAY could not be set on " +
                                     std::to_string(r.failed) + " of " + std::to_string(r.accepted) +
                                     " subscriber connections");
  else if (r.set > 0)
    ROS_DEBUG("hair_sim: TCP_NODELAY set on %d of %d subscriber connections", r.set, r.accepted);
}

void HairSimNode::warnThrottled(const std::string& what, const std::string& text, double every) {
  const ros::WallTime now = ros::WallTime::now();
  auto it = last_warning_.find(what);
  if (it != last_warning_.end()) {
    const double since = (now - it->second.first).toSec();
    if (every > 0.0 ? since < every : it->second.second == text && since < 2.0) return;
  }
  last_warning_[what] = {now, text};
  ROS_WARN("%s", text.c_str());
}

void HairSimNode::onTimer(const ros::TimerEvent&) {
  guarded("the timer", [&] {
    // A fallback while no tf comes in (the hair still settles and is published at publish_rate).
    // Not between two tf messages that come in more slowly than publish_rate: the outputs follow the tf
    // then, and the timer would only send the last one again (same stamp, same hair).
    const double wait = std::max(1.5 / config_.publish_rate, 2.0 * tf_interval_);
    if ((ros::WallTime::now() - last_tf_update_).toSec() < wait) return;
    update(false);
  });
}

void HairSimNode::update(bool from_tf) {
  const double dt = config_.physics.substep;
  Iso3 latest_pose;
  ros::Time target;
  if (from_tf) {
    const ros::WallTime now = ros::WallTime::now();
    // The longest recent interval, forgotten by 10 % a message: two messages that arrive together (a
    // busy host) do not make the tf look fast.
    if (!last_tf_update_.isZero())
      tf_interval_ = std::max(std::min((now - last_tf_update_).toSec(), max_tf_age_), 0.9 * tf_interval_);
    last_tf_update_ = now;
  }
  applyLiveSettings();
  if (!lookupPose(config_.head_frame, ros::Time(0), latest_pose, &target)) {
    diagnostics_->headPoseMissing();
    return;
  }
  diagnostics_->headPose(target);
  // Time went backwards when the newest head pose is older than the one before (not than sim_time_, which
  // runs ahead of it while a stale head is held).
  if (!started_ || target + ros::Duration(1e-9) < newest_head_stamp_) {
    if (started_)
      ROS_WARN("hair_sim: time went backwards (%.3f -> %.3f): starting again from the rest shape",
               newest_head_stamp_.toSec(), target.toSec());
    if (!lookupPose(config_.head_frame, target, latest_pose)) return;
    simulator_->reset();
    head_.reset(latest_pose);
    if (started_ && events_.size() > 0) {
      ROS_WARN("hair_sim: %zu scheduled events dropped with the time jump", events_.size());
      events_.clear();
    }
    // A wind ramp started at a time now in the future would hold the wind before it: the last wind blows.
    wind_.settle();
    snapSimTime(target);
    next_publish_ = ros::Time();
    started_ = true;
    ROS_INFO("hair_sim: following %s in %s from t = %.3f", config_.head_frame.c_str(),
             config_.world_frame.c_str(), target.toSec());
  }
  newest_head_stamp_ = target;
  // A stale head pose (none newer than max_tf_age): the head is held where it was last seen and the hair
  // goes on moving, up to max_tf_age behind the clock (so that a pose coming in again is not taken for
  // time going backwards).
  const ros::Time clock = ros::Time::now();
  const double age = clock.toSec() - target.toSec();
  const bool stale = age > max_tf_age_;
  if (stale != head_stale_) {
    if (stale)
      ROS_WARN(
          "hair_sim: the head pose (tf %s -> %s) is %.2f s old (max_tf_age %.2f s): holding the head "
          "where it was last seen",
          config_.world_frame.c_str(), config_.head_frame.c_str(), age, max_tf_age_);
    else
      ROS_INFO("hair_sim: head pose (tf %s -> %s) fresh again", config_.world_frame.c_str(),
               config_.head_frame.c_str());
    head_stale_ = stale;
  }
  if (stale && last_body_frames_.size() == config_.bodies.size()) {
    const ros::Time hold_until = clock - ros::Duration(max_tf_age_);
    const Iso3 held = head_.state().pose;
    int held_steps = 0;
    const ros::WallTime held_start = ros::WallTime::now();
    for (ros::Time t = gridTime(sim_step_ + 1, dt); t <= hold_until && held_steps < max_substeps_per_update_;
         t = gridTime(sim_step_ + 1, dt)) {
      stepTo(t, head_.update(held, dt), last_body_frames_);  // bodies on the head are held with it
      ++sim_step_;
      sim_time_ = t;
      ++held_steps;
    }
    if (gridTime(sim_step_ + 1, dt) <= hold_until) {  // a long stall: skip ahead
      ROS_WARN_THROTTLE(5.0,
                        "hair_sim: %.3f s behind the clock with the head held; skipping ahead "
                        "(max_substeps_per_update %d)",
                        (hold_until - sim_time_).toSec(), max_substeps_per_update_);
      diagnostics_->droppedInput("stale head: skipped " + formatDouble((hold_until - sim_time_).toSec()) +
                                 " s (max_substeps_per_update)");
      snapSimTime(hold_until);
    }
    status_steps_ += held_steps;
    diagnostics_->addSubsteps(held_steps, (ros::WallTime::now() - held_start).toSec());
    target = sim_time_;
    latest_pose = held;
  }
  // Fixed substeps up to the newest head pose, the pose sampled (interpolated by tf) at each.
  const ros::WallTime wall_start = ros::WallTime::now();
  int steps = 0;
  std::vector<Iso3> frames(config_.bodies.size(), Iso3::Identity());
  for (ros::Time t = gridTime(sim_step_ + 1, dt); t <= target; t = gridTime(sim_step_ + 1, dt)) {
    if (steps == max_substeps_per_update_) {
      ROS_WARN_THROTTLE(5.0,
                        "hair_sim: %.3f s behind the head pose; skipping ahead (max_substeps_per_update %d)",
                        (target - sim_time_).toSec(), max_substeps_per_update_);
      diagnostics_->droppedInput("head poses: skipped " + formatDouble((target - sim_time_).toSec()) +
                                 " s (max_substeps_per_update)");
      Iso3 pose;
      snapSimTime(target);
      if (lookupPose(config_.head_frame, sim_time_, pose)) head_.reset(pose);
      break;
    }
    applyLiveSettings();
    Iso3 pose;
    if (!lookupPose(config_.head_frame, t, pose)) {
      // The newest pose is there (target), this earlier one is not: tf dropped it (a gap in the head's tf
      // longer than its cache, a clock that jumped) or never had it. Waiting would never bring it: the hair
      // goes to the newest pose rigidly, as in a teleport.
      ROS_WARN(
          "hair_sim: no head pose at t = %.3f, %.3f s before the newest (%.3f; the tf cache holds %.1f s): "
          "skipping ahead to it, the hair carried rigidly",
          t.toSec(), target.toSec() - t.toSec(), target.toSec(), tf_buffer_.getCacheLength().toSec());
      diagnostics_->droppedInput("head poses: skipped " + formatDouble(target.toSec() - sim_time_.toSec()) +
                                 " s (no longer in tf)");
      snapSimTime(target);
      head_.reset(latest_pose);
      simulator_->forgetBodyMotion();
      break;
    }
    bool frames_ok = true;
    for (std::size_t b = 0; b < config_.bodies.size() && frames_ok; ++b)
      frames_ok = bodyFrameAt(b, t, frames[b]);
    if (!frames_ok) break;
    const HeadState head = head_.update(pose, dt);
    if (head_.teleported()) {
      simulator_->forgetBodyMotion();
      ROS_WARN(
          "hair_sim: the head jumped %.3f m and %.3f rad within one substep at t = %.3f (teleport_distance "
          "%.3f m, teleport_angle %.3f rad): the hair goes with it rigidly",
          head_.jumpDistance(), head_.jumpAngle(), t.toSec(), teleport_distance_, teleport_angle_);
      diagnostics_->droppedInput("head teleport of " + formatDouble(head_.jumpDistance()) + " m, " +
                                 formatDouble(head_.jumpAngle()) + " rad");
    }
    stepTo(t, head, frames);
    diagnostics_->penetrations(simulator_->penetrationCount(), simulator_->maxPenetration());
    ++sim_step_;
    sim_time_ = t;
    last_body_frames_ = frames;
    ++steps;
  }
  events_.dropEndedBefore(sim_time_.toSec());
  status_steps_ += steps;
  status_step_seconds_ += (ros::WallTime::now() - wall_start).toSec();
  diagnostics_->addSubsteps(steps, (ros::WallTime::now() - wall_start).toSec());
  // An output is due at every multiple of 1/publish_rate s of ROS time, on the first head pose stamped at or
  // after it (so the markers go out right after the tf they reflect, and a replay of the same tf publishes
  // the same states); the timer publishes whenever it acts.
  const double period = 1.0 / config_.publish_rate;
  if (from_tf && !next_publish_.isZero() && target < next_publish_) return;
  next_publish_ = gridTime(gridIndexAtOrBefore(target, period) + 1, period);
  if (last_body_frames_.size() != config_.bodies.size()) {
    for (std::size_t b = 0; b < config_.bodies.size(); ++b)
      if (!lookupPose(config_.bodies[b].frame, sim_time_, frames[b])) return;
    last_body_frames_ = frames;
  }
  // The outputs show the newest head pose: caught up with it, the hair's shape (kept in the head
  // frame) is that of the last substep, at most one substep before `target`, carried rigidly with the
  // head for the rest of the way, and stamped `target`, so that they reflect the tf that came in, with
  // the bodies at the same time. Otherwise (a lookup failed) the last substep's pose and time.
  ros::Time stamp = sim_time_;
  Iso3 pose = head_.state().pose;
  std::vector<Iso3>* body_frames = &last_body_frames_;
  if (target > sim_time_ && gridTime(sim_step_ + 1, dt) > target) {
    bool frames_ok = true;
    for (std::size_t b = 0; b < config_.bodies.size() && frames_ok; ++b)
      frames_ok = lookupPose(config_.bodies[b].frame, target, frames[b]);
    if (frames_ok) {
      stamp = target;
      pose = latest_pose;
      body_frames = &frames;
    }
  }
  publishOutputs(stamp, pose, *body_frames);
  publishBodies(stamp, *body_frames);
  ++status_publishes_;
  if (from_tf) {  // from the tf message's arrival to the outputs handed to the transport
    const double took = (ros::WallTime::now() - tf_received_).toSec();
    status_tf_to_output_sum_ += took;
    status_tf_to_output_max_ = std::max(status_tf_to_output_max_, took);
    ++status_tf_outputs_;
  }
  const double since = (ros::WallTime::now() - status_since_).toSec();
  if (since >= 5.0) {
    ROS_INFO(
        "hair_sim: %zu strips, simulated %.0f substeps/s (target %.0f), %.3f ms per substep, %.1f Hz output, "
        "tf arrival -> output sent %.2f ms mean %.2f ms max",
        simulator_->hairstyle().strips.size(), status_steps_ / since, 1.0 / dt,
        status_steps_ > 0 ? 1e3 * status_step_seconds_ / status_steps_ : 0.0, status_publishes_ / since,
        status_tf_outputs_ > 0 ? 1e3 * status_tf_to_output_sum_ / status_tf_outputs_ : 0.0,
        1e3 * status_tf_to_output_max_);
    status_tf_to_output_sum_ = status_tf_to_output_max_ = 0.0;
    status_tf_outputs_ = 0;
    status_since_ = ros::WallTime::now();
    status_steps_ = 0;
    status_step_seconds_ = 0.0;
    status_publishes_ = 0;
  }
}

void HairSimNode::publishOutputs(const ros::Time& stamp, const Iso3& pose,
                                 const std::vector<Iso3>& body_frames) {
  simulator_->positionsWorld(pose, world_points_);
  // hair_state as a shared pointer: zero-copy to subscribers in the same process (a nodelet manager), which
  // keep the message; roscpp serialises for the others within publish() and keeps no reference. A message
  // that only this node still holds is filled again in place (its buffers already have the size).
  // hair_markers (768 kB by default) is written from the meshes straight into the serialised message.
  if (state_pub_.getNumSubscribers() > 0) {
    if (!state_msg_ || !state_msg_.unique()) state_msg_ = boost::make_shared<hair_sim_msgs::HairState>();
    fillHairState(*simulator_, world_points_, config_.world_frame, stamp, *state_msg_);
    state_pub_.publish(state_msg_);
  }
  if (markers_pub_.getNumSubscribers() == 0) return;
  bodies_scratch_.clear();
  for (std::size_t b = 0; b < config_.bodies.size() && b < body_frames.size(); ++b)
    bodies_scratch_.push_back(config_.bodies[b].shape.transformed(body_frames[b]));
  meshes_->build(world_points_, simulator_->stripOffsets(), simulator_->hairstyle().scalp.transformed(pose),
                 bodies_scratch_);
  // Too large for any subscriber (and gigabytes to build at every output, which stalled the hair): not sent.
  const std::uint64_t bound = hairMarkersSizeBound(*meshes_, render_mode_, strands_per_strip_);
  if (bound > kMaxMarkersBytes) {
    const LevelOfDetail& level = meshes_->levelOfDetail();
    char text[400];
    std::snprintf(
        text, sizeof(text),
        "hair_sim: hair_markers not sent: it would take up to %.2f GB (render_mode %s, "
        "strands_per_strip %d, level of detail %d x %d), more than the 1 GB a ROS subscriber accepts: "
        "lower ~strands_per_strip or the level of detail (hair_state goes on)",
        1e-9 * static_cast<double>(bound), renderModeName(render_mode_), strands_per_strip_,
        level.samples_across, level.samples_along);
    warnThrottled("markers size", text, 5.0);
    return;
  }
  // A namespace the new render mode drops is deleted in the messages of the next second (at least 3).
  markers_view_.update(*meshes_, render_mode_, strands_per_strip_, config_.world_frame, stamp,
                       std::max(3, static_cast<int>(std::ceil(config_.publish_rate))));
  markers_pub_.publish(markers_view_);
}

void HairSimNode::publishBodies(const ros::Time& stamp, const std::vector<Iso3>& frames) {
  // Latched, and sent again only when a body moved (1e-6 m or rad): world-fixed bodies go out once.
  bool changed = published_body_frames_.size() != frames.size();
  for (std::size_t b = 0; !changed && b < frames.size(); ++b)
    changed = (frames[b].matrix() - published_body_frames_[b].matrix()).cwiseAbs().maxCoeff() > 1e-6;
  if (!changed) return;
  published_body_frames_ = frames;
  bodies_pub_.publish(
      makeBodyMarkers(config_.bodies, frames, config_.head_frame, config_.world_frame, stamp));
}

ros::Time HairSimNode::gridTime(int64_t k, double period) {
  const long double s = static_cast<long double>(k) * static_cast<long double>(period);
  const long double whole = std::floor(s);
  int64_t nsec = std::llround((s - whole) * 1e9L);
  int64_t sec = static_cast<int64_t>(whole);
  if (nsec >= 1000000000) {
    nsec -= 1000000000;
    ++sec;
  }
  return ros::Time(static_cast<uint32_t>(sec), static_cast<uint32_t>(nsec));
}

int64_t HairSimNode::gridIndexAtOrBefore(const ros::Time& t, double period) {
  const long double s = static_cast<long double>(t.sec) + static_cast<long double>(t.nsec) * 1e-9L;
  auto k = static_cast<int64_t>(std::floor(s / static_cast<long double>(period)));
  while (k > 0 && gridTime(k, period) > t) --k;  // rounding of the quotient
  while (gridTime(k + 1, period) <= t) ++k;
  return k;
}

void HairSimNode::snapSimTime(const ros::Time& t) {
  sim_step_ = gridIndexAtOrBefore(t, config_.physics.substep);
  sim_time_ = gridTime(sim_step_, config_.physics.substep);
}

void HairSimNode::applyLiveSettings() {
  LiveSettings s;
  if (!live_ || !live_->takePending(s)) return;
  try {
    simulator_->setParameters(s.physics);  // between two substeps: the state is kept
  } catch (const std::invalid_argument& e) {
    ROS_WARN("hair_sim: live parameters not applied: %s", e.what());
    return;
  }
  config_.physics = s.physics;  // a later reset KEEP_SHAPE rebuilds with them
  wind_scale_ = s.wind_scale;
  parseRenderMode(s.render_mode, &render_mode_);  // (LiveParameters checked the name)
  if (s.mesh.level_of_detail.samples_across != mesh_options_.level_of_detail.samples_across ||
      s.mesh.level_of_detail.samples_along != mesh_options_.level_of_detail.samples_along ||
      s.mesh.max_triangles != mesh_options_.max_triangles) {
    mesh_options_ = s.mesh;
    makeMeshBuilder();
    const LevelOfDetail& level = meshes_->levelOfDetail();
    ROS_INFO("hair_sim: level of detail now %d x %d: %lld triangles", level.samples_across,
             level.samples_along, static_cast<long long>(meshes_->triangleCount()));
  }
}

}  // namespace hair_sim
