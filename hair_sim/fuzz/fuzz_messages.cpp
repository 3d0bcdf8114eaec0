/// Fuzz entry for the node's message handling without a ROS master: bytes deserialised with
/// ros::serialization into hair_sim_msgs/Wind, hair_sim_msgs/HairEvent and tf2_msgs/TFMessage, turned into
/// core inputs the way hair_sim_node does it (checkWind from InputChecks, HairSimNode::schedule ->
/// eventFromMsg -> Event::findProblem -> EventSchedule::add, the transforms through checkTransform into a
/// tf2 buffer and tf2::transformToEigen into HeadMotionEstimator with the node's default teleport limits,
/// Simulator::forgetBodyMotion after a teleport), then a few Simulator substeps with them (a small
/// hairstyle: the first strips of config/hairstyles/default.yaml, the bodies of config/hair_sim.yaml).
///
/// Input: byte 0 = flags, then three chunks, each a little-endian uint16 length and that many bytes: the
/// serialised Wind, HairEvent and TFMessage (a chunk that does not deserialise is dropped, as roscpp drops
/// it). A bug aborts: a crash, an unexpected exception, undefined behaviour (under the sanitizers), an event
/// eventFromMsg accepts but EventSchedule::add refuses, or a non-finite control point.
///
/// With HAIR_SIM_FUZZ_STATE_HASH set in the environment, each input that reaches the substeps prints the
/// FNV-1a hash of the final control points (head frame) on stdout (the test PinchMemoryGivesTheSameBits
/// compares them between two builds).
///
/// The glue between those calls (lookups, holding the last good pose, the order of the calls) is
/// HairSimNode's, repeated here because the node needs a master: keep it in step with HairSimNode::onTf,
/// update and schedule.
#include <console_bridge/console.h>
#include <ros/serialization.h>
#include <tf2/buffer_core.h>
#include <tf2/exceptions.h>
#include <tf2_eigen/tf2_eigen.h>

#include <hair_sim_msgs/HairEvent.h>
#include <hair_sim_msgs/Wind.h>
#include <tf2_msgs/TFMessage.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <string>

#include "../test/SimdDump.hpp"
#include "hair_sim/core/Simulator.hpp"
#include "hair_sim/core/model/HairstyleIO.hpp"
#include "hair_sim/core/model/SimConfig.hpp"
#include "hair_sim/ros/HairMessages.hpp"
#include "hair_sim/ros/InputChecks.hpp"

#ifndef HAIR_SIM_REPO_ROOT
#error "HAIR_SIM_REPO_ROOT must name the repository (config/ is read from it)"
#endif

namespace {

using namespace hair_sim;

constexpr int kMaxSubsteps = 12;
constexpr int kStrips = 6;
const char* const kWorld = "world";
const char* const kHead = "head";

[[noreturn]] void bug(const std::string& what) {
  std::fprintf(stderr, "fuzz_messages: BUG: %s\n", what.c_str());
  std::fflush(stderr);
  std::abort();
}

struct Fixture {
  SimConfig config;
  Hairstyle style;
  Fixture() {
    config = loadSimConfig(std::string(HAIR_SIM_REPO_ROOT) + "/config/hair_sim.yaml");
    style = loadHairstyle(config.hairstyle_file);
    style.strips.resize(kStrips);
    console_bridge::setLogLevel(console_bridge::CONSOLE_BRIDGE_LOG_NONE);  // tf2's rejections
  }
};

/// Next chunk: uint16 length + bytes (truncated to what is left).
bool nextChunk(const std::uint8_t*& p, const std::uint8_t* end, const std::uint8_t** chunk, std::size_t* n) {
  if (end - p < 2) return false;
  std::size_t len = static_cast<std::size_t>(p[0]) | (static_cast<std::size_t>(p[1]) << 8);
  p += 2;
  len = std::min(len, static_cast<std::size_t>(end - p));
  *chunk = p;
  *n = len;
  p += len;
  return true;
}

template <typename M>
bool deserialize(const std::uint8_t* data, std::size_t n, M* msg) {
  try {
    ros::serialization::IStream stream(const_cast<std::uint8_t*>(data), static_cast<std::uint32_t>(n));
    ros::serialization::deserialize(stream, *msg);
    return true;
  } catch (const ros::serialization::StreamOverrunException&) {
    return false;  // roscpp drops such a message
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const Fixture fixture;
  if (size < 1) return 0;
  const std::uint8_t flags = data[0];
  const std::uint8_t* p = data + 1;
  const std::uint8_t* end = data + size;
  const double dt = fixture.config.physics.substep;

  // Transforms first: a buffer holding world -> head at the stamps given (frame names fixed so that the
  // node's lookup finds them; the values and times are the fuzzer's).
  tf2::BufferCore buffer(ros::Duration(10.0));
  const std::uint8_t* chunk[3] = {nullptr, nullptr, nullptr};
  std::size_t length[3] = {0, 0, 0};
  for (int i = 0; i < 3; ++i)
    if (!nextChunk(p, end, &chunk[i], &length[i])) break;

  tf2_msgs::TFMessage tf;
  // ros::serialization resizes a vector to the length it reads before reading the elements: a bogus
  // length asks for gigabytes (roscpp would do the same; see docs/robustness-suites.md). A serialised
  // TransformStamped takes at least 76 bytes.
  bool have_tf = false;
  if (length[2] >= 4) {
    std::uint32_t count = 0;
    std::memcpy(&count, chunk[2], 4);
    if (static_cast<std::uint64_t>(count) * 76u <= length[2] - 4)
      have_tf = deserialize(chunk[2], length[2], &tf);
  }
  double first_stamp = std::numeric_limits<double>::infinity(), last_stamp = -first_stamp;
  if (have_tf) {
    int k = 0;
    for (const geometry_msgs::TransformStamped& given : tf.transforms) {
      // HairSimNode::onTf: a bad transform never enters the buffer, a non-unit quaternion is normalised.
      geometry_msgs::TransformStamped t;
      bool normalised = false;
      const std::string problem = checkTransform(given, &t, &normalised);
      if (!problem.empty()) continue;
      t.header.frame_id = kWorld;
      t.child_frame_id = kHead;
      // Stamps: the fuzzer's, folded into the first few substeps (bit 0 of flags: keep them as given).
      if (!(flags & 1)) t.header.stamp = ros::Time(1.0 + 0.5 * dt * k);
      ++k;
      try {
        buffer.setTransform(t, "fuzz", (flags & 2) != 0);
      } catch (const tf2::TransformException&) {
        continue;  // the node logs and goes on
      }
      first_stamp = std::min(first_stamp, t.header.stamp.toSec());
      last_stamp = std::max(last_stamp, t.header.stamp.toSec());
    }
  }

  // Wind (its frame_id taken as the world frame).
  Vec3 wind = Vec3::Zero();
  hair_sim_msgs::Wind wind_msg;
  if (chunk[0] && deserialize(chunk[0], length[0], &wind_msg) && checkWind(wind_msg).empty())
    wind = Vec3(wind_msg.velocity.x, wind_msg.velocity.y, wind_msg.velocity.z);

  // Event, as HairSimNode::schedule (stamp zero = now: t = 1 s here).
  EventSchedule schedule;
  hair_sim_msgs::HairEvent event_msg;
  if (chunk[1] && deserialize(chunk[1], length[1], &event_msg)) {
    const Vec3 v(event_msg.vector.x, event_msg.vector.y, event_msg.vector.z);
    const double start = event_msg.header.stamp.isZero() ? 1.0 : event_msg.header.stamp.toSec();
    Event event;
    std::string problem;
    if (eventFromMsg(event_msg, v, start, &event, &problem)) {
      try {
        schedule.add(event);
      } catch (const std::exception& e) {
        bug(std::string("eventFromMsg accepted an event that EventSchedule::add refuses: ") + e.what());
      }
    } else if (problem.empty()) {
      bug("eventFromMsg refused an event without saying why");
    }
  }

  // Substeps as HairSimNode::update: from the earliest pose, each pose sampled from the buffer.
  Simulator sim(fixture.style, fixture.config.physics, fixture.config.bodies);
  HeadMotionEstimator head(0.02);  // the node's defaults: head_smoothing, teleport_distance, teleport_angle
  head.setTeleportLimits(0.5, 1.0);
  double t0 = 1.0;
  Iso3 pose = Iso3::Identity();
  bool started = false;
  if (first_stamp <= last_stamp) {
    try {
      pose = tf2::transformToEigen(buffer.lookupTransform(kWorld, kHead, ros::Time(first_stamp)));
      t0 = first_stamp;
      started = pose.matrix().allFinite();
    } catch (const tf2::TransformException&) {
    }
  }
  if (!started) pose = Iso3::Identity();
  head.reset(pose);
  std::vector<Iso3> frames(fixture.config.bodies.size());
  for (int n = 1; n <= kMaxSubsteps; ++n) {
    const double t = t0 + n * dt;
    if (started && t <= last_stamp + 1e-9) {
      try {
        const Iso3 p = tf2::transformToEigen(buffer.lookupTransform(kWorld, kHead, ros::Time(t)));
        if (p.matrix().allFinite()) pose = p;  // the node holds the last good pose
      } catch (const tf2::TransformException&) {
        break;
      }
    }
    const EventSample events = schedule.sample(t, fixture.config.physics.gravity);
    if (!(events.wind.allFinite() && events.gravity.allFinite() && events.head_rotation.allFinite()))
      bug("event sample not finite at t = " + std::to_string(t));
    StepInputs in;
    in.head = head.update(pose, dt);
    if (head.teleported()) sim.forgetBodyMotion();
    in.wind = wind + events.wind;
    in.turbulence = &events.turbulence;
    in.gravity = &events.gravity;
    for (std::size_t b = 0; b < frames.size(); ++b)
      frames[b] = fixture.config.bodies[b].frame == kHead ? in.head.pose : Iso3::Identity();
    in.body_frames = frames;
    sim.step(in);
    for (const Vec3& x : sim.positionsHead())
      if (!x.allFinite()) bug("non-finite control point after substep " + std::to_string(n));
  }
  if (std::getenv("HAIR_SIM_FUZZ_STATE_HASH")) {
    const std::uint64_t h =
        simd_dump::hashOf(sim.positionsHead().data(), sim.positionsHead().size() * sizeof(Vec3));
    std::printf("state_hash %016llx\n", static_cast<unsigned long long>(h));
  }
  return 0;
}
