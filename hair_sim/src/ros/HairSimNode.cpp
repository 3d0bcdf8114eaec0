#include "hair_sim/ros/HairSimNode.hpp"

#include <geometry_msgs/TransformStamped.h>
#include <hair_sim_msgs/HairState.h>
#include <tf2_eigen/tf2_eigen.h>
#include <visualization_msgs/MarkerArray.h>

#include <cmath>
#include <stdexcept>

#include "hair_sim/core/model/HairstyleIO.hpp"
#include "hair_sim/core/util/YamlReader.hpp"

namespace hair_sim {

namespace {

std::invalid_argument badParam(const std::string& name, const std::string& value, const std::string& rule) {
  return std::invalid_argument("parameter ~" + name + ": '" + value + "' " + rule);
}

geometry_msgs::Point toPoint(const Vec3& p) {
  geometry_msgs::Point q;
  q.x = p.x();
  q.y = p.y();
  q.z = p.z();
  return q;
}

std_msgs::ColorRGBA toColor(const Rgba& c) {
  std_msgs::ColorRGBA q;
  q.r = c.r;
  q.g = c.g;
  q.b = c.b;
  q.a = c.a;
  return q;
}

}  // namespace

HairSimNode::HairSimNode(ros::NodeHandle nh, ros::NodeHandle private_nh)
    : nh_(nh), pnh_(private_nh), tf_listener_(tf_buffer_) {
  readParameters();
  rebuild(loadHairstyle(config_.hairstyle_file));
  markers_pub_ = nh_.advertise<visualization_msgs::MarkerArray>("hair_markers", 2);
  bodies_pub_ = nh_.advertise<visualization_msgs::MarkerArray>("collision_bodies", 1, true);
  state_pub_ = nh_.advertise<hair_sim_msgs::HairState>("hair_state", 2);
  wind_sub_ = nh_.subscribe("wind", 10, &HairSimNode::onWind, this);
  reset_srv_ = nh_.advertiseService("reset", &HairSimNode::onReset, this);
  timer_ = nh_.createTimer(ros::Duration(1.0 / config_.publish_rate), &HairSimNode::onTimer, this);
  status_since_ = ros::WallTime::now();
  ROS_INFO(
      "hair_sim: %zu strips, %d control points, %zu bodies, substep %.5f s, publishing at %.1f Hz in '%s', "
      "head frame '%s', level of detail %d x %d",
      simulator_->hairstyle().strips.size(), simulator_->controlPointCount(), config_.bodies.size(),
      config_.physics.substep, config_.publish_rate, config_.world_frame.c_str(), config_.head_frame.c_str(),
      meshes_->levelOfDetail().samples_across, meshes_->levelOfDetail().samples_along);
}

void HairSimNode::readParameters() {
  if (!pnh_.getParam("config_file", config_file_) || config_file_.empty())
    throw badParam("config_file", config_file_, "is required: the path of config/hair_sim.yaml");
  config_ = loadSimConfig(config_file_);  // names file, key, line and value on error
  // Individual parameters override the file (launch file arguments).
  std::string frame;
  if (pnh_.getParam("world_frame", frame)) {
    if (!isValidFrameName(frame)) throw badParam("world_frame", frame, "is not a valid tf frame name");
    config_.world_frame = frame;
  }
  if (pnh_.getParam("head_frame", frame)) {
    if (!isValidFrameName(frame)) throw badParam("head_frame", frame, "is not a valid tf frame name");
    config_.head_frame = frame;
  }
  if (config_.world_frame == config_.head_frame)
    throw badParam("head_frame", config_.head_frame, "must differ from world_frame");
  double rate = 0.0;
  if (pnh_.getParam("publish_rate", rate)) {
    if (!(std::isfinite(rate) && rate > 0.0 && rate <= 1.0 / config_.physics.substep))
      throw badParam("publish_rate", formatDouble(rate), "must be in (0, 1/substep] Hz");
    config_.publish_rate = rate;
  }
  std::string mode = "mesh";
  pnh_.getParam("render_mode", mode);
  if (mode == "mesh")
    render_mode_ = RenderMode::Mesh;
  else if (mode == "strands")
    render_mode_ = RenderMode::Strands;
  else if (mode == "both")
    render_mode_ = RenderMode::Both;
  else
    throw badParam("render_mode", mode, "must be mesh, strands or both");
  int across = 2, along = 4, max_triangles = 0;
  pnh_.getParam("samples_across", across);
  pnh_.getParam("samples_along", along);
  pnh_.getParam("max_triangles", max_triangles);
  if (across < 1 || across > 64) throw badParam("samples_across", std::to_string(across), "must be in 1..64");
  if (along < 1 || along > 64) throw badParam("samples_along", std::to_string(along), "must be in 1..64");
  if (max_triangles < 0)
    throw badParam("max_triangles", std::to_string(max_triangles), "must be >= 0 (0 = off)");
  mesh_options_.level_of_detail = LevelOfDetail{across, along};
  mesh_options_.max_triangles = max_triangles;
  pnh_.getParam("max_substeps_per_update", max_substeps_per_update_);
  if (max_substeps_per_update_ < 1)
    throw badParam("max_substeps_per_update", std::to_string(max_substeps_per_update_), "must be >= 1");
  double smoothing = 0.02;
  pnh_.getParam("head_smoothing", smoothing);
  if (!(std::isfinite(smoothing) && smoothing >= 0.0 && smoothing <= 1.0))
    throw badParam("head_smoothing", formatDouble(smoothing), "must be in [0, 1] s");
  head_ = HeadMotionEstimator(smoothing);
  pnh_.getParam("strands_per_strip", strands_per_strip_);
  if (strands_per_strip_ < 1)
    throw badParam("strands_per_strip", std::to_string(strands_per_strip_), "must be >= 1");
}

void HairSimNode::rebuild(Hairstyle hairstyle) {
  simulator_ = std::make_unique<Simulator>(std::move(hairstyle), config_.physics, config_.bodies);
  meshes_ = std::make_unique<HairMeshBuilder>(simulator_->hairstyle(), mesh_options_);
}

bool HairSimNode::lookupPose(const std::string& frame, const ros::Time& stamp, Iso3& pose, ros::Time* found) {
  if (frame == config_.world_frame) {
    pose = Iso3::Identity();
    if (found) *found = stamp;
    return true;
  }
  try {
    const geometry_msgs::TransformStamped t =
        tf_buffer_.lookupTransform(config_.world_frame, frame, stamp, ros::Duration(0.0));
    pose = tf2::transformToEigen(t);
    if (found) *found = t.header.stamp;
    if (!pose.matrix().allFinite()) {
      ROS_WARN_THROTTLE(5.0, "hair_sim: tf %s -> %s has non-finite values; holding the last good pose",
                        config_.world_frame.c_str(), frame.c_str());
      return false;
    }
    return true;
  } catch (const tf2::TransformException& e) {
    ROS_WARN_THROTTLE(5.0, "hair_sim: no tf %s -> %s at %.3f: %s", config_.world_frame.c_str(), frame.c_str(),
                      stamp.toSec(), e.what());
    return false;
  }
}

Vec3 HairSimNode::windAt(double t) const {
  const double s = wind_ramp_ > 0.0 ? std::min(1.0, std::max(0.0, (t - wind_start_) / wind_ramp_)) : 1.0;
  Vec3 w = (1.0 - s) * wind_from_ + s * wind_to_;
  if (turbulence_ > 0.0) {
    // Smooth, deterministic fluctuation: incommensurate sines per axis, relative to the mean speed.
    const double speed = w.norm();
    const Vec3 noise(std::sin(2.1 * t) + 0.5 * std::sin(5.3 * t + 1.0),
                     std::sin(1.7 * t + 2.0) + 0.5 * std::sin(4.1 * t), 0.5 * std::sin(2.9 * t + 0.5));
    w += turbulence_ * speed * noise / 1.5;
  }
  return w;
}

void HairSimNode::onWind(const hair_sim_msgs::Wind::ConstPtr& msg) {
  const Vec3 v(msg->velocity.x, msg->velocity.y, msg->velocity.z);
  if (!v.allFinite() || !std::isfinite(msg->turbulence) || !std::isfinite(msg->ramp_time)) {
    ROS_WARN_THROTTLE(2.0,
                      "hair_sim: ignored a Wind message with a non-finite velocity, turbulence or ramp_time");
    return;
  }
  if (msg->turbulence < 0.0 || msg->ramp_time < 0.0) {
    ROS_WARN_THROTTLE(2.0,
                      "hair_sim: ignored a Wind message: turbulence %.3f and ramp_time %.3f must be >= 0",
                      msg->turbulence, msg->ramp_time);
    return;
  }
  if (v.norm() > 1000.0) {
    ROS_WARN_THROTTLE(2.0, "hair_sim: ignored a Wind message: speed %.1f m/s is above 1000 m/s", v.norm());
    return;
  }
  Vec3 world = v;
  const std::string frame = msg->header.frame_id;
  if (!frame.empty() && frame != config_.world_frame) {
    Iso3 pose;
    if (!lookupPose(frame, ros::Time(0), pose)) {
      ROS_WARN_THROTTLE(2.0, "hair_sim: ignored a Wind message in frame '%s': no tf to '%s'", frame.c_str(),
                        config_.world_frame.c_str());
      return;
    }
    world = pose.linear() * v;
  }
  const double now = started_ ? sim_time_.toSec() : 0.0;
  wind_from_ = windAt(now);
  wind_to_ = world;
  wind_start_ = now;
  wind_ramp_ = msg->ramp_time;
  turbulence_ = msg->turbulence;
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

void HairSimNode::onTimer(const ros::TimerEvent&) {
  const double dt = config_.physics.substep;
  Iso3 latest_pose;
  ros::Time target;
  if (!lookupPose(config_.head_frame, ros::Time(0), latest_pose, &target)) return;
  if (!started_ || target + ros::Duration(1e-9) < sim_time_) {
    if (started_)
      ROS_WARN("hair_sim: time went backwards (%.3f -> %.3f): starting again from the rest shape",
               sim_time_.toSec(), target.toSec());
    if (!lookupPose(config_.head_frame, target, latest_pose)) return;
    simulator_->reset();
    head_.reset(latest_pose);
    sim_time_ = target;
    started_ = true;
    ROS_INFO("hair_sim: following %s in %s from t = %.3f", config_.head_frame.c_str(),
             config_.world_frame.c_str(), target.toSec());
  }
  // Fixed substeps up to the newest head pose, the pose sampled (interpolated by tf) at each.
  const ros::WallTime wall_start = ros::WallTime::now();
  int steps = 0;
  std::vector<Iso3> frames(config_.bodies.size(), Iso3::Identity());
  while ((sim_time_ + ros::Duration(dt)) <= target) {
    if (steps == max_substeps_per_update_) {
      ROS_WARN_THROTTLE(5.0,
                        "hair_sim: %.3f s behind the head pose; skipping ahead (max_substeps_per_update %d)",
                        (target - sim_time_).toSec(), max_substeps_per_update_);
      Iso3 pose;
      if (lookupPose(config_.head_frame, target, pose)) head_.reset(pose);
      sim_time_ = target;
      break;
    }
    const ros::Time t = sim_time_ + ros::Duration(dt);
    Iso3 pose;
    if (!lookupPose(config_.head_frame, t, pose)) break;
    bool frames_ok = true;
    for (std::size_t b = 0; b < config_.bodies.size() && frames_ok; ++b)
      frames_ok = lookupPose(config_.bodies[b].frame, t, frames[b]);
    if (!frames_ok) break;
    StepInputs in;
    in.head = head_.update(pose, dt);
    in.wind = windAt(t.toSec());
    in.body_frames = frames;
    simulator_->step(in);
    sim_time_ = t;
    last_body_frames_ = frames;
    ++steps;
  }
  status_steps_ += steps;
  status_step_seconds_ += (ros::WallTime::now() - wall_start).toSec();
  if (last_body_frames_.size() != config_.bodies.size()) {
    for (std::size_t b = 0; b < config_.bodies.size(); ++b)
      if (!lookupPose(config_.bodies[b].frame, sim_time_, frames[b])) return;
    last_body_frames_ = frames;
  }
  publishOutputs(sim_time_);
  publishBodies(sim_time_, last_body_frames_);
  ++status_publishes_;
  const double since = (ros::WallTime::now() - status_since_).toSec();
  if (since >= 5.0) {
    ROS_INFO(
        "hair_sim: %zu strips, simulated %.0f substeps/s (target %.0f), %.3f ms per substep, %.1f Hz output",
        simulator_->hairstyle().strips.size(), status_steps_ / since, 1.0 / dt,
        status_steps_ > 0 ? 1e3 * status_step_seconds_ / status_steps_ : 0.0, status_publishes_ / since);
    status_since_ = ros::WallTime::now();
    status_steps_ = 0;
    status_step_seconds_ = 0.0;
    status_publishes_ = 0;
  }
}

void HairSimNode::publishOutputs(const ros::Time& stamp) {
  const Iso3& pose = head_.state().pose;
  simulator_->positionsWorld(pose, world_points_);
  const std::vector<int>& offsets = simulator_->stripOffsets();
  const auto& strips = simulator_->hairstyle().strips;
  if (state_pub_.getNumSubscribers() > 0) {
    hair_sim_msgs::HairState state;
    state.header.stamp = stamp;
    state.header.frame_id = config_.world_frame;
    state.step = static_cast<std::uint64_t>(simulator_->stepCount());
    state.strips.resize(strips.size());
    for (std::size_t s = 0; s < strips.size(); ++s) {
      hair_sim_msgs::StripState& out = state.strips[s];
      out.columns = static_cast<std::uint32_t>(strips[s].columns);
      out.rows = static_cast<std::uint32_t>(strips[s].rows);
      out.hair_length = strips[s].hair_length;
      out.color = toColor(strips[s].color);
      out.points.reserve(static_cast<std::size_t>(strips[s].pointCount()));
      for (int p = 0; p < strips[s].pointCount(); ++p)
        out.points.push_back(toPoint(world_points_[static_cast<std::size_t>(offsets[s] + p)]));
    }
    state_pub_.publish(state);
  }
  if (markers_pub_.getNumSubscribers() == 0) return;
  std::vector<Ellipsoid> bodies;
  for (std::size_t b = 0; b < config_.bodies.size() && b < last_body_frames_.size(); ++b)
    bodies.push_back(config_.bodies[b].shape.transformed(last_body_frames_[b]));
  meshes_->build(world_points_, offsets, simulator_->hairstyle().scalp.transformed(pose), bodies);
  visualization_msgs::MarkerArray array;
  visualization_msgs::Marker base;
  base.header.stamp = stamp;
  base.header.frame_id = config_.world_frame;
  base.pose.orientation.w = 1.0;
  base.scale.x = base.scale.y = base.scale.z = 1.0;
  base.color.r = base.color.g = base.color.b = base.color.a = 1.0f;
  base.action = visualization_msgs::Marker::ADD;
  if (render_mode_ != RenderMode::Strands) {
    // One merged TRIANGLE_LIST: every strip, both windings (both faces visible), per-vertex RGBA.
    visualization_msgs::Marker m = base;
    m.ns = "hair";
    m.id = 0;
    m.type = visualization_msgs::Marker::TRIANGLE_LIST;
    std::vector<std::uint32_t> indices;
    for (std::size_t s = 0; s < meshes_->meshes().size(); ++s) {
      const StripMesh& mesh = meshes_->meshes()[s];
      const std::vector<Rgba>& colours = meshes_->colours()[s];
      indices.clear();
      Tessellator::appendTriangles(mesh, 0, true, indices);
      for (std::uint32_t k : indices) {
        m.points.push_back(toPoint(mesh.positions[k]));
        m.colors.push_back(toColor(colours[k]));
      }
    }
    array.markers.push_back(m);
  }
  if (render_mode_ != RenderMode::Mesh) {
    visualization_msgs::Marker m = base;
    m.ns = "strands";
    m.id = 0;
    m.type = visualization_msgs::Marker::LINE_LIST;
    m.scale.x = 0.0015;  // line width (m)
    std::vector<Vec3> points;
    std::vector<Rgba> colours;
    for (std::size_t s = 0; s < meshes_->meshes().size(); ++s)
      HairLook::strandLines(meshes_->meshes()[s], strands_per_strip_, points, &meshes_->colours()[s],
                            &colours);
    for (std::size_t k = 0; k < points.size(); ++k) {
      m.points.push_back(toPoint(points[k]));
      m.colors.push_back(toColor(colours[k]));
    }
    array.markers.push_back(m);
  }
  markers_pub_.publish(array);
}

void HairSimNode::publishBodies(const ros::Time& stamp, const std::vector<Iso3>& frames) {
  // Latched, and sent again only when a body moved (1e-6 m or rad): world-fixed bodies go out once.
  bool changed = published_body_frames_.size() != frames.size();
  for (std::size_t b = 0; !changed && b < frames.size(); ++b)
    changed = (frames[b].matrix() - published_body_frames_[b].matrix()).cwiseAbs().maxCoeff() > 1e-6;
  if (!changed) return;
  published_body_frames_ = frames;
  visualization_msgs::MarkerArray array;
  for (std::size_t b = 0; b < config_.bodies.size() && b < frames.size(); ++b) {
    const Body& body = config_.bodies[b];
    const Ellipsoid e = body.shape.transformed(frames[b]);
    visualization_msgs::Marker m;
    m.header.stamp = stamp;
    m.header.frame_id = config_.world_frame;
    m.ns = "bodies";
    m.id = static_cast<int>(b);
    m.type = visualization_msgs::Marker::SPHERE;
    m.action = visualization_msgs::Marker::ADD;
    m.pose.position = toPoint(e.center());
    const Eigen::Quaterniond q(e.rotation());
    m.pose.orientation.x = q.x();
    m.pose.orientation.y = q.y();
    m.pose.orientation.z = q.z();
    m.pose.orientation.w = q.w();
    m.scale.x = 2.0 * e.radii().x();
    m.scale.y = 2.0 * e.radii().y();
    m.scale.z = 2.0 * e.radii().z();
    // The head opaque (the hair sits on a visible head), the rest of the body translucent.
    const bool head = body.frame == config_.head_frame;
    m.color.r = 0.85f;
    m.color.g = 0.68f;
    m.color.b = 0.56f;
    m.color.a = head ? 1.0f : 0.45f;
    array.markers.push_back(m);
  }
  bodies_pub_.publish(array);
}

}  // namespace hair_sim
