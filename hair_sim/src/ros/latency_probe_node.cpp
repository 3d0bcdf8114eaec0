/// latency_probe: measures hair_sim_node's outputs from outside, as a C++ viewer (rviz) receives them.
/// Subscribes to hair_state and (with ~markers true) hair_markers, waits for the first message, lets the
/// subscription settle, then for ~seconds records each message's latency: ROS time at receipt (after
/// deserialisation, as a viewer's callback sees it) minus header.stamp, which is the stamp of the newest
/// head tf the output reflects (head_driver stamps tf when it sends it). Prints the line "recording" when
/// the window starts, then one JSON object:
///   {"seconds", "state": {...}, "markers": {...}} with messages, rate_hz, latency_ms_p50/p99/max, bytes.
/// Used by scripts/bench_node.py (./run.sh bench). Exits 1 if no message came within ~wait (s, 30).
///
/// The load of test/load.test (issue 8), from here so that the harness costs the 2-core host little:
/// ~wind_rate (Hz, 0 = none) publishes hair_sim_msgs/Wind on `wind` from its own thread on an absolute
/// schedule (a late thread sends the messages it missed at once), a 3 m/s wind in `world` turning at
/// 0.5 rad/s, every message different; ~count_tf (false) counts /tf messages. The JSON then has "input":
/// {"tf_hz", "wind_hz"}, the messages received and sent per second over the window.
/// ~tcp_nodelay (false): subscribe to the outputs with ros::TransportHints().tcpNoDelay().
#include <hair_sim_msgs/HairState.h>
#include <hair_sim_msgs/Wind.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <tf2_msgs/TFMessage.h>
#include <visualization_msgs/MarkerArray.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

namespace {

struct Series {
  std::vector<double> latencies;  ///< s
  double bytes = 0.0;
  bool recording = false;
  bool seen = false;

  void add(const ros::Time& stamp, std::size_t size) {
    seen = true;
    if (!recording) return;
    latencies.push_back((ros::Time::now() - stamp).toSec());
    bytes += static_cast<double>(size);
  }

  std::string json(double seconds) const {
    std::vector<double> v = latencies;
    std::sort(v.begin(), v.end());
    auto at = [&](double p) {
      if (v.empty()) return 0.0;
      const auto k = static_cast<std::size_t>(p / 100.0 * static_cast<double>(v.size() - 1) + 0.5);
      return 1e3 * v[std::min(k, v.size() - 1)];
    };
    char out[256];
    std::snprintf(
        out, sizeof out,
        "{\"messages\": %zu, \"rate_hz\": %.3f, \"latency_ms_p50\": %.3f, \"latency_ms_p99\": %.3f, "
        "\"latency_ms_max\": %.3f, \"bytes\": %.0f}",
        v.size(), static_cast<double>(v.size()) / seconds, at(50), at(99), v.empty() ? 0.0 : 1e3 * v.back(),
        v.empty() ? 0.0 : bytes / static_cast<double>(v.size()));
    return out;
  }
};

/// Publishes Wind at `rate` Hz on an absolute schedule until `stop`; `sent` counts while `counting`.
void windLoad(const ros::Publisher& pub, double rate, const std::atomic<bool>& stop,
              const std::atomic<bool>& counting, std::atomic<long>& sent) {
  hair_sim_msgs::Wind w;
  w.header.frame_id = "world";
  const auto period = std::chrono::duration<double>(1.0 / rate);
  const auto start = std::chrono::steady_clock::now();
  for (long k = 0; !stop && ros::ok(); ++k) {
    const double a = 0.5 * static_cast<double>(k) / rate;  // rad
    w.header.stamp = ros::Time::now();
    w.velocity.x = 3.0 * std::cos(a);
    w.velocity.y = 3.0 * std::sin(a);
    pub.publish(w);
    if (counting) ++sent;
    std::this_thread::sleep_until(start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                              static_cast<double>(k + 1) * period));
  }
}

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "latency_probe", ros::init_options::AnonymousName);
  ros::NodeHandle nh, pnh("~");
  const double seconds = pnh.param("seconds", 10.0);
  const double wait = pnh.param("wait", 30.0);
  const bool markers = pnh.param("markers", true);
  const double wind_rate = pnh.param("wind_rate", 0.0);
  const bool count_tf = pnh.param("count_tf", false);
  const bool tcp_nodelay = pnh.param("tcp_nodelay", false);
  const ros::TransportHints hints = tcp_nodelay ? ros::TransportHints().tcpNoDelay() : ros::TransportHints();
  if (!(seconds > 0.0 && wait > 0.0 && wind_rate >= 0.0 && wind_rate <= 100000.0)) {
    ROS_FATAL("latency_probe: ~seconds (%g) and ~wait (%g) must be > 0, ~wind_rate (%g) in [0, 1e5] Hz",
              seconds, wait, wind_rate);
    return 2;
  }
  std::atomic<bool> stop{false}, counting{false};
  std::atomic<long> wind_sent{0};
  long tf_received = 0;
  ros::Subscriber tf_sub;
  if (count_tf)
    tf_sub = nh.subscribe<tf2_msgs::TFMessage>("/tf", 2000, [&](const tf2_msgs::TFMessage::ConstPtr&) {
      if (counting) ++tf_received;
    });
  ros::Publisher wind_pub;
  std::thread wind_thread;
  if (wind_rate > 0.0) {
    wind_pub = nh.advertise<hair_sim_msgs::Wind>("wind", 100);
    wind_thread = std::thread(windLoad, std::cref(wind_pub), wind_rate, std::cref(stop), std::cref(counting),
                              std::ref(wind_sent));
  }
  struct Joiner {
    std::atomic<bool>& stop;
    std::thread& thread;
    ~Joiner() {
      stop = true;
      if (thread.joinable()) thread.join();
    }
  } joiner{stop, wind_thread};
  Series state, mesh;
  ros::Subscriber state_sub = nh.subscribe<hair_sim_msgs::HairState>(
      "hair_state", 100,
      [&](const hair_sim_msgs::HairState::ConstPtr& m) {
        state.add(m->header.stamp, ros::serialization::serializationLength(*m));
      },
      ros::VoidConstPtr(), hints);
  ros::Subscriber markers_sub;
  if (markers)
    markers_sub = nh.subscribe<visualization_msgs::MarkerArray>(
        "hair_markers", 100,
        [&](const visualization_msgs::MarkerArray::ConstPtr& m) {
          if (!m->markers.empty())
            mesh.add(m->markers.front().header.stamp, ros::serialization::serializationLength(*m));
        },
        ros::VoidConstPtr(), hints);
  auto spinFor = [](double s) {
    const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(s);
    while (ros::ok() && ros::WallTime::now() < end)
      ros::getGlobalCallbackQueue()->callAvailable(ros::WallDuration(0.01));
  };
  const ros::WallTime give_up = ros::WallTime::now() + ros::WallDuration(wait);
  while (ros::ok() && !(state.seen && (!markers || mesh.seen)) && ros::WallTime::now() < give_up)
    spinFor(0.05);
  if (!(state.seen && (!markers || mesh.seen))) {
    std::printf("{\"error\": \"no %s within %g s\"}\n", state.seen ? "hair_markers" : "hair_state", wait);
    return 1;
  }
  spinFor(2.0);                // let the subscriptions settle
  std::printf("recording\n");  // bench_node.py starts its CPU window here
  std::fflush(stdout);
  state.recording = mesh.recording = true;
  counting = true;
  const ros::WallTime start = ros::WallTime::now();
  spinFor(seconds);
  counting = false;
  const double took = (ros::WallTime::now() - start).toSec();
  std::printf("{\"seconds\": %.3f, \"state\": %s", took, state.json(took).c_str());
  if (markers) std::printf(", \"markers\": %s", mesh.json(took).c_str());
  if (count_tf || wind_rate > 0.0)
    std::printf(", \"input\": {\"tf_hz\": %.3f, \"wind_hz\": %.3f}", static_cast<double>(tf_received) / took,
                static_cast<double>(wind_sent.load()) / took);
  std::printf("}\n");
  return 0;
}
