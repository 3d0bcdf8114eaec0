/// head_driver: broadcasts the tf world_frame -> head_frame as a teleoperated head would move it, to drive
/// hair_sim_node in demos and tests.
///
/// Modes (private parameter ~mode):
///   programme (default)  base pose + idle sway (a small smooth multi-sine on x, y, z, roll, pitch, yaw,
///   faded
///                        in over the first seconds) + a repeating programme of nods (pitch), shakes (yaw)
///                        and turns (yaw to one side, hold, back; alternating sides).
///   still                the head fixed at the base pose.
///   translate            the base pose, then at ~translate_start s one smooth move of ~translate_distance m
///                        along +y in world_frame over ~translate_duration s, then still (for tests).
///
/// Every motion is built from 0.5 - 0.5 cos(.) ramps and windows, so the pose is C1 in time (zero velocity at
/// every start and stop). Time is ros::Time::now() (simulated time with use_sim_time), counted from the first
/// valid time the node sees; the pose at time t is the pure function head_driver::headPoseAt().
///
/// Parameters (private): world_frame (world), head_frame (head), rate (Hz, 100), mode (programme),
/// base_x, base_y, base_z (m; 0, 0, 1.6), sway_position_amplitude (m, 0.004), sway_angle_amplitude (rad,
/// 0.03), sway_frequency (Hz, lowest sway component, 0.2), seed (int, 1: sway phases and frequencies),
/// nod_amplitude (rad, 0.25), shake_amplitude (rad, 0.5), turn_amplitude (rad, 0.7),
/// motion_frequency (Hz, 1.0: a nod or shake lasts two cycles, 2 / motion_frequency s; so does a turn),
/// motion_period (s, 4.0: from the start of one motion to the start of the next, >= 2 / motion_frequency;
/// each motion is preceded by the rest of its period), motions (comma-separated list of nod, shake, turn,
/// default "nod,shake,turn"; also a YAML list; empty = sway only), translate_distance (m, 0.3),
/// translate_duration (s, 0.5), translate_start (s, 2.0).
/// A bad value logs ROS_FATAL naming the parameter and its value, and the node exits with status 1.
///
/// Head-motion events (hair_sim_msgs/HairEvent of type nod, shake, turn or tilt on the topic `events`,
/// also what hair_sim_node's `trigger` service passes on) turn the head about its origin on top of the
/// mode's motion, from their stamp (zero = on receipt), composed in order of start; other types are
/// hair_sim_node's and are ignored here.
#include <geometry_msgs/TransformStamped.h>
#include <hair_sim_msgs/HairEvent.h>
#include <ros/ros.h>
#include <tf2/LinearMath/Quaternion.h>
#include <tf2_ros/transform_broadcaster.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "hair_sim/core/events/EventSchedule.hpp"
#include "hair_sim/ros/HairMessages.hpp"

namespace head_driver {

constexpr double kPi = 3.14159265358979323846;
/// The idle sway fades in over this time (s), so the head starts exactly at the base pose, at rest.
constexpr double kSwayFadeIn = 2.0;

enum class Mode { Programme, Still, Translate };
enum class Motion { Nod, Shake, Turn };

/// Head pose in the world frame: position (m) and fixed-axis roll, pitch, yaw (rad),
/// R = Rz(yaw) Ry(pitch) Rx(roll) (tf2::Quaternion::setRPY). Positive pitch tips the nose (+x) down.
struct HeadPose {
  double x = 0.0, y = 0.0, z = 0.0;
  double roll = 0.0, pitch = 0.0, yaw = 0.0;
};

/// Everything headPoseAt() depends on. Defaults are the node's parameter defaults.
struct MotionSettings {
  Mode mode = Mode::Programme;
  double base_x = 0.0, base_y = 0.0, base_z = 1.6;  // m
  // Idle sway (programme mode).
  double sway_position_amplitude = 0.004;  // m, bound on |x|, |y| offsets (z: half of it)
  double sway_angle_amplitude = 0.03;      // rad, bound on |pitch|, |yaw| offsets (roll: half of it)
  double sway_frequency = 0.2;             // Hz, lowest component
  std::int64_t seed = 1;
  // Programme.
  double nod_amplitude = 0.25;    // rad, pitch down
  double shake_amplitude = 0.5;   // rad, yaw either way
  double turn_amplitude = 0.7;    // rad, yaw held
  double motion_frequency = 1.0;  // Hz
  double motion_period = 4.0;     // s, start to start
  std::vector<Motion> motions{Motion::Nod, Motion::Shake, Motion::Turn};
  // Translate mode.
  double translate_distance = 0.3;  // m along +y
  double translate_duration = 0.5;  // s
  double translate_start = 2.0;     // s
};

/// 0 for u <= 0, 1 for u >= 1, 0.5 - 0.5 cos(pi u) between: C1 (zero slope at both ends).
inline double smoothStep(double u) {
  if (u <= 0.0) return 0.0;
  if (u >= 1.0) return 1.0;
  return 0.5 - 0.5 * std::cos(kPi * u);
}

/// Window on [0, duration]: rises with smoothStep over `ramp`, 1 in the middle, falls symmetrically; 0
/// outside.
inline double window(double tau, double duration, double ramp) {
  if (tau <= 0.0 || tau >= duration) return 0.0;
  return smoothStep(tau / ramp) * smoothStep((duration - tau) / ramp);
}

/// Duration of one programme motion (s): two cycles at motion_frequency.
inline double motionDuration(const MotionSettings& s) { return 2.0 / s.motion_frequency; }

namespace detail {

inline std::uint64_t splitMix64(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9E3779B97F4A7C15ULL);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

/// Uniform in [0, 1), the same on every platform for a given seed.
inline double unitRandom(std::uint64_t& state) {
  return static_cast<double>(splitMix64(state) >> 11) * (1.0 / 9007199254740992.0);
}

}  // namespace detail

/// Idle sway offsets [x, y, z, roll, pitch, yaw] at time t (s): per axis three sines of weights 0.5, 0.3, 0.2
/// (so |offset| <= its amplitude) at incommensurate frequencies from sway_frequency, phases from the seed,
/// multiplied by a C1 fade-in over kSwayFadeIn.
inline std::array<double, 6> swayAt(const MotionSettings& s, double t) {
  static constexpr std::array<double, 3> kRatios{1.0, 2.13, 3.71};
  static constexpr std::array<double, 3> kWeights{0.5, 0.3, 0.2};
  const std::array<double, 6> amplitude{s.sway_position_amplitude,       s.sway_position_amplitude,
                                        0.5 * s.sway_position_amplitude, 0.5 * s.sway_angle_amplitude,
                                        s.sway_angle_amplitude,          s.sway_angle_amplitude};
  std::uint64_t state = static_cast<std::uint64_t>(s.seed);
  const double fade = smoothStep(t / kSwayFadeIn);
  std::array<double, 6> out{};
  for (std::size_t axis = 0; axis < out.size(); ++axis) {
    double sum = 0.0;
    for (std::size_t j = 0; j < kRatios.size(); ++j) {
      const double frequency = s.sway_frequency * kRatios[j] * (0.8 + 0.4 * detail::unitRandom(state));
      const double phase = 2.0 * kPi * detail::unitRandom(state);
      sum += kWeights[j] * std::sin(2.0 * kPi * frequency * t + phase);
    }
    out[axis] = fade * amplitude[axis] * sum;
  }
  return out;
}

/// Pose of the head at time t (s) since the start (t < 0 is taken as 0). Pure: depends on its arguments only.
inline HeadPose headPoseAt(const MotionSettings& s, double t) {
  if (!(t > 0.0)) t = 0.0;  // also maps NaN to 0
  HeadPose p;
  p.x = s.base_x;
  p.y = s.base_y;
  p.z = s.base_z;
  switch (s.mode) {
    case Mode::Still:
      return p;
    case Mode::Translate:
      p.y += s.translate_distance * smoothStep((t - s.translate_start) / s.translate_duration);
      return p;
    case Mode::Programme:
      break;
  }
  const std::array<double, 6> sway = swayAt(s, t);
  p.x += sway[0];
  p.y += sway[1];
  p.z += sway[2];
  p.roll += sway[3];
  p.pitch += sway[4];
  p.yaw += sway[5];
  if (s.motions.empty()) return p;
  // Slot k covers [k P, (k + 1) P): rest first, then motions[k % n] during its last D seconds.
  const double period = s.motion_period;
  const double duration = motionDuration(s);
  const double f = s.motion_frequency;
  const double slot_index = std::floor(t / period);
  const double tau = t - slot_index * period - (period - duration);
  if (tau <= 0.0 || tau >= duration) return p;
  const std::size_t n = s.motions.size();
  const auto k = static_cast<std::uint64_t>(slot_index);
  const std::size_t position = static_cast<std::size_t>(k % n);
  const double ramp = 0.5 / f;
  switch (s.motions[position]) {
    case Motion::Nod:  // two nods down and up
      p.pitch += s.nod_amplitude * window(tau, duration, ramp) * 0.5 * (1.0 - std::cos(2.0 * kPi * f * tau));
      break;
    case Motion::Shake:  // two shakes left-right
      p.yaw += s.shake_amplitude * window(tau, duration, ramp) * std::sin(2.0 * kPi * f * tau);
      break;
    case Motion::Turn: {  // turn (ramp 0.5/f), hold (1/f), turn back (0.5/f); sides alternate
      const auto turns_in = [&](std::size_t end) {
        return static_cast<std::uint64_t>(std::count(
            s.motions.begin(), s.motions.begin() + static_cast<std::ptrdiff_t>(end), Motion::Turn));
      };
      const std::uint64_t before = (k / n) * turns_in(n) + turns_in(position);
      const double side = before % 2 == 0 ? 1.0 : -1.0;
      p.yaw += side * s.turn_amplitude * window(tau, duration, ramp);
      break;
    }
  }
  return p;
}

/// Parses "nod, shake,turn" (case-sensitive, spaces around names ignored). Throws std::invalid_argument
/// naming the bad entry. An empty or blank string gives an empty list.
inline std::vector<Motion> parseMotions(const std::string& text) {
  std::vector<Motion> out;
  if (text.find_first_not_of(" \t") == std::string::npos) return out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    const std::size_t b = item.find_first_not_of(" \t");
    const std::size_t e = item.find_last_not_of(" \t");
    const std::string name = b == std::string::npos ? std::string() : item.substr(b, e - b + 1);
    if (name == "nod")
      out.push_back(Motion::Nod);
    else if (name == "shake")
      out.push_back(Motion::Shake);
    else if (name == "turn")
      out.push_back(Motion::Turn);
    else
      throw std::invalid_argument("entry '" + name + "' is not one of nod, shake, turn");
  }
  if (!text.empty() && text.back() == ',')
    throw std::invalid_argument("entry '' is not one of nod, shake, turn");
  return out;
}

/// The ROS node: reads and validates the parameters, then broadcasts headPoseAt(now - start) at ~rate Hz.
class HeadDriver {
 public:
  /// Throws std::invalid_argument "parameter ~name: 'value' rule" on a bad parameter.
  HeadDriver(ros::NodeHandle nh, ros::NodeHandle private_nh) : nh_(nh), pnh_(private_nh) {
    readParameters();
    timer_ = nh_.createTimer(ros::Duration(1.0 / rate_), &HeadDriver::onTimer, this);
    // Room for a burst of events (a scenario sent at once), as hair_sim_node has: roscpp drops unseen what
    // does not fit in the queue.
    events_sub_ = nh_.subscribe("events", 1024, &HeadDriver::onEvent, this);
  }

 private:
  static std::invalid_argument badParam(const std::string& name, const std::string& value,
                                        const std::string& rule) {
    return std::invalid_argument("parameter ~" + name + ": '" + value + "' " + rule);
  }

  static std::string toString(double v) {
    std::ostringstream os;
    os.precision(10);
    os << v;
    return os.str();
  }

  std::string rawValue(const std::string& name) const {
    XmlRpc::XmlRpcValue raw;
    if (!pnh_.getParam(name, raw)) return "?";
    std::ostringstream os;
    raw.write(os);
    return os.str();
  }

  /// A number parameter (ints are accepted as doubles); the default when not set; throws when it is set to
  /// something that is not a number or is not finite.
  double getNumber(const std::string& name, double fallback) const {
    if (!pnh_.hasParam(name)) return fallback;
    double v = 0.0;
    if (!pnh_.getParam(name, v)) throw badParam(name, rawValue(name), "is not a number");
    if (!std::isfinite(v)) throw badParam(name, toString(v), "must be finite");
    return v;
  }

  std::string getString(const std::string& name, const std::string& fallback) const {
    if (!pnh_.hasParam(name)) return fallback;
    std::string v;
    if (!pnh_.getParam(name, v)) throw badParam(name, rawValue(name), "is not a string");
    return v;
  }

  static void require(bool ok, const std::string& name, double value, const std::string& rule) {
    if (!ok) throw badParam(name, toString(value), rule);
  }

  std::string getFrame(const std::string& name, const std::string& fallback) const {
    const std::string frame = getString(name, fallback);
    if (frame.empty() || frame.front() == '/' || frame.find_first_of(" \t") != std::string::npos)
      throw badParam(name, frame, "is not a valid tf frame name (non-empty, no leading '/', no spaces)");
    return frame;
  }

  void readParameters() {
    world_frame_ = getFrame("world_frame", "world");
    head_frame_ = getFrame("head_frame", "head");
    if (world_frame_ == head_frame_)
      throw badParam("head_frame", head_frame_, "must differ from world_frame");

    rate_ = getNumber("rate", 100.0);
    require(rate_ > 0.0 && rate_ <= 10000.0, "rate", rate_, "must be in (0, 10000] Hz");

    const std::string mode = getString("mode", "programme");
    if (mode == "programme")
      settings_.mode = Mode::Programme;
    else if (mode == "still")
      settings_.mode = Mode::Still;
    else if (mode == "translate")
      settings_.mode = Mode::Translate;
    else
      throw badParam("mode", mode, "must be programme, still or translate");

    settings_.base_x = getNumber("base_x", settings_.base_x);
    settings_.base_y = getNumber("base_y", settings_.base_y);
    settings_.base_z = getNumber("base_z", settings_.base_z);

    settings_.sway_position_amplitude =
        getNumber("sway_position_amplitude", settings_.sway_position_amplitude);
    require(settings_.sway_position_amplitude >= 0.0 && settings_.sway_position_amplitude <= 0.1,
            "sway_position_amplitude", settings_.sway_position_amplitude, "must be in [0, 0.1] m");
    settings_.sway_angle_amplitude = getNumber("sway_angle_amplitude", settings_.sway_angle_amplitude);
    require(settings_.sway_angle_amplitude >= 0.0 && settings_.sway_angle_amplitude <= 0.5,
            "sway_angle_amplitude", settings_.sway_angle_amplitude, "must be in [0, 0.5] rad");
    settings_.sway_frequency = getNumber("sway_frequency", settings_.sway_frequency);
    require(settings_.sway_frequency > 0.0 && settings_.sway_frequency <= 5.0, "sway_frequency",
            settings_.sway_frequency, "must be in (0, 5] Hz");
    if (pnh_.hasParam("seed")) {
      XmlRpc::XmlRpcValue seed;
      pnh_.getParam("seed", seed);
      if (seed.getType() != XmlRpc::XmlRpcValue::TypeInt)
        throw badParam("seed", rawValue("seed"), "is not an integer");
      settings_.seed = static_cast<int>(seed);
    }

    settings_.nod_amplitude = getNumber("nod_amplitude", settings_.nod_amplitude);
    require(settings_.nod_amplitude >= 0.0 && settings_.nod_amplitude <= kPi / 2.0, "nod_amplitude",
            settings_.nod_amplitude, "must be in [0, pi/2] rad");
    settings_.shake_amplitude = getNumber("shake_amplitude", settings_.shake_amplitude);
    require(settings_.shake_amplitude >= 0.0 && settings_.shake_amplitude <= kPi / 2.0, "shake_amplitude",
            settings_.shake_amplitude, "must be in [0, pi/2] rad");
    settings_.turn_amplitude = getNumber("turn_amplitude", settings_.turn_amplitude);
    require(settings_.turn_amplitude >= 0.0 && settings_.turn_amplitude <= kPi / 2.0, "turn_amplitude",
            settings_.turn_amplitude, "must be in [0, pi/2] rad");
    settings_.motion_frequency = getNumber("motion_frequency", settings_.motion_frequency);
    require(settings_.motion_frequency > 0.0 && settings_.motion_frequency <= 20.0, "motion_frequency",
            settings_.motion_frequency, "must be in (0, 20] Hz");
    settings_.motion_period = getNumber("motion_period", settings_.motion_period);
    const double duration = motionDuration(settings_);
    require(settings_.motion_period >= duration * (1.0 - 1e-9), "motion_period", settings_.motion_period,
            "must be at least the motion duration 2 / motion_frequency = " + toString(duration) + " s");
    readMotions();

    settings_.translate_distance = getNumber("translate_distance", settings_.translate_distance);
    require(std::abs(settings_.translate_distance) <= 100.0, "translate_distance",
            settings_.translate_distance, "must be in [-100, 100] m");
    settings_.translate_duration = getNumber("translate_duration", settings_.translate_duration);
    require(settings_.translate_duration > 0.0, "translate_duration", settings_.translate_duration,
            "must be > 0 s");
    settings_.translate_start = getNumber("translate_start", settings_.translate_start);
    require(settings_.translate_start >= 0.0, "translate_start", settings_.translate_start, "must be >= 0 s");

    ROS_INFO("head_driver: %s -> %s at %.1f Hz, mode %s, base [%.3f, %.3f, %.3f]", world_frame_.c_str(),
             head_frame_.c_str(), rate_, mode.c_str(), settings_.base_x, settings_.base_y, settings_.base_z);
  }

  void readMotions() {
    if (!pnh_.hasParam("motions")) return;
    XmlRpc::XmlRpcValue raw;
    pnh_.getParam("motions", raw);
    std::string text;
    if (raw.getType() == XmlRpc::XmlRpcValue::TypeString) {
      text = static_cast<std::string>(raw);
    } else if (raw.getType() == XmlRpc::XmlRpcValue::TypeArray) {
      for (int i = 0; i < raw.size(); ++i) {
        if (raw[i].getType() != XmlRpc::XmlRpcValue::TypeString)
          throw badParam("motions", rawValue("motions"),
                         "must be a comma-separated string or a list of names");
        text += (i > 0 ? "," : "") + static_cast<std::string>(raw[i]);
      }
    } else {
      throw badParam("motions", rawValue("motions"), "must be a comma-separated string or a list of names");
    }
    try {
      settings_.motions = parseMotions(text);
    } catch (const std::invalid_argument& e) {
      throw badParam("motions", text, e.what());
    }
    if (settings_.motions.empty() && settings_.mode == Mode::Programme)
      ROS_INFO("head_driver: ~motions is empty: idle sway only");
  }

  void onEvent(const hair_sim_msgs::HairEvent::ConstPtr& msg) {
    hair_sim::EventType type;
    if (hair_sim::parseEventType(msg->type, &type) && !hair_sim::isHeadMotion(type)) return;  // the hair's
    const ros::Time start = msg->header.stamp.isZero() ? ros::Time::now() : msg->header.stamp;
    hair_sim::Event event;
    std::string problem;
    if (!hair_sim::eventFromMsg(*msg, hair_sim::Vec3::Zero(), start.toSec(), &event, &problem)) {
      // The same warning again at most every 2 s, a different one at once (as hair_sim_node's): a flood
      // of one bad event does not fill the log, and a second, different one is not hidden behind it.
      const std::string text = "head_driver: ignored a HairEvent (" + msg->type + "): " + problem;
      const ros::WallTime wall = ros::WallTime::now();
      if (text != last_event_warning_ || (wall - last_event_warning_time_).toSec() >= 2.0) {
        ROS_WARN("%s", text.c_str());
        last_event_warning_ = text;
        last_event_warning_time_ = wall;
      }
      return;
    }
    events_.add(event);
    ROS_INFO("head_driver: %s of %.3f rad at %.3f Hz from t = %.3f s%s", msg->type.c_str(), event.amplitude,
             event.frequency, start.toSec(),
             event.duration > 0.0 ? (" for " + toString(event.duration) + " s").c_str() : " until replaced");
  }

  /// The timer (roscpp drops the ticks it is late for) sends the messages due on an absolute schedule of
  /// ~rate per second from the start, so that a late callback (a loaded host) sends the ones it missed at
  /// once and the rate holds on average; more than 0.1 s behind, the schedule skips ahead. Each message
  /// is stamped when it is sent.
  void onTimer(const ros::TimerEvent&) {
    const ros::Time now = ros::Time::now();
    if (now.isZero()) return;  // simulated time not yet received
    if (start_.isZero() || now < last_stamp_) {
      if (!start_.isZero()) {
        ROS_WARN("head_driver: time went backwards (%.3f -> %.3f): starting the motion again%s",
                 last_stamp_.toSec(), now.toSec(), events_.size() > 0 ? ", events dropped" : "");
        events_.clear();
      }
      start_ = now;
      last_stamp_ = ros::Time();
      sent_ = 0;
    }
    const auto due = static_cast<int64_t>(std::floor((now - start_).toSec() * rate_)) + 1;
    const auto backlog_cap = static_cast<int64_t>(std::ceil(0.1 * rate_));
    if (due - sent_ > backlog_cap) sent_ = due - 1;  // a stall: skip ahead rather than flood
    for (; sent_ < due; ++sent_) {
      const ros::Time stamp = ros::Time::now();
      if (stamp <= last_stamp_) return;  // same stamp again (simulated clock): tf2 would reject it
      sendPose(stamp);
    }
  }

  void sendPose(const ros::Time& now) {
    last_stamp_ = now;
    const HeadPose pose = headPoseAt(settings_, (now - start_).toSec());
    geometry_msgs::TransformStamped msg;
    msg.header.stamp = now;
    msg.header.frame_id = world_frame_;
    msg.child_frame_id = head_frame_;
    msg.transform.translation.x = pose.x;
    msg.transform.translation.y = pose.y;
    msg.transform.translation.z = pose.z;
    tf2::Quaternion q;
    q.setRPY(pose.roll, pose.pitch, pose.yaw);
    if (events_.size() > 0) {
      const Eigen::Quaterniond turn(events_.sample(now.toSec(), hair_sim::Vec3::Zero()).head_rotation);
      q = q * tf2::Quaternion(turn.x(), turn.y(), turn.z(), turn.w());
      events_.dropEndedBefore(now.toSec());
    }
    q.normalize();
    msg.transform.rotation.x = q.x();
    msg.transform.rotation.y = q.y();
    msg.transform.rotation.z = q.z();
    msg.transform.rotation.w = q.w();
    broadcaster_.sendTransform(msg);
  }

  ros::NodeHandle nh_, pnh_;
  tf2_ros::TransformBroadcaster broadcaster_;
  ros::Timer timer_;
  ros::Subscriber events_sub_;
  hair_sim::EventSchedule events_;  ///< head motions, in seconds of ROS time
  std::string last_event_warning_;  ///< the last "ignored a HairEvent" warning, and when it was given
  ros::WallTime last_event_warning_time_;
  MotionSettings settings_;
  std::string world_frame_ = "world";
  std::string head_frame_ = "head";
  double rate_ = 100.0;
  ros::Time start_;
  ros::Time last_stamp_;
  int64_t sent_ = 0;  ///< messages sent since start_ (the schedule)
};

}  // namespace head_driver

// A unit test can #define HEAD_DRIVER_NO_MAIN and #include this file to test head_driver::headPoseAt().
#ifndef HEAD_DRIVER_NO_MAIN
int main(int argc, char** argv) {
  ros::init(argc, argv, "head_driver");
  // The handles outlive the try block: when the last NodeHandle goes, roscpp shuts down and the ROS_FATAL
  // below would be swallowed.
  ros::NodeHandle nh;
  ros::NodeHandle private_nh("~");
  try {
    head_driver::HeadDriver driver(nh, private_nh);
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL("head_driver: %s", e.what());
    return 1;
  }
  return 0;
}
#endif
