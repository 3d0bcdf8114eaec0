#pragma once
/// hair_sim_node's health on /diagnostics (diagnostic_updater): five statuses, each OK/WARN/ERROR by the
/// thresholds below, published every ~diagnostic_period (1 s):
///   "simulated rate"  substeps per second of ROS time vs the target 1/substep
///   "step time"       wall time per substep vs the substep
///   "head tf"         age of the newest head pose (now - its stamp); ERROR while there is none
///   "penetration"     control points inside an inflated body after a substep (0 by construction)
///   "inputs"          dropped inputs: rejected wind messages, substeps skipped (catch-up cap, tf gaps)
/// The node reports what happens (addSubsteps, headPose, ...); the window restarts at every publish.
#include <diagnostic_msgs/DiagnosticStatus.h>
#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/ros.h>

#include <mutex>
#include <string>

namespace hair_sim {

struct DiagnosticThresholds {
  double rate_warn = 0.9;      ///< simulated rate below this fraction of the target: WARN
  double rate_error = 0.5;     ///< ... below this fraction: ERROR
  double step_warn = 0.5;      ///< mean wall time per substep above this fraction of the substep: WARN
  double step_error = 1.0;     ///< ... above this fraction (slower than real time): ERROR
  double tf_age_warn = 0.25;   ///< s: newest head pose older than this: WARN
  double tf_age_error = 1.0;   ///< s: older than this (or none): ERROR
  int penetration_warn = 1;    ///< control points inside a body at least this many: WARN
  int penetration_error = 10;  ///< ... at least this many: ERROR
  int dropped_warn = 1;        ///< dropped inputs in one window at least this many: WARN
  int dropped_error = 10;      ///< ... at least this many: ERROR

  /// Reads the ~diag_* parameters over the defaults; throws std::invalid_argument naming a bad one.
  static DiagnosticThresholds read(const ros::NodeHandle& private_nh);
};

class HairSimDiagnostics {
 public:
  using Level = unsigned char;  ///< diagnostic_msgs::DiagnosticStatus::OK, WARN or ERROR

  /// `name` prefixes the status names (the node's name); `hardware_id` identifies the avatar.
  HairSimDiagnostics(ros::NodeHandle nh, ros::NodeHandle private_nh, const std::string& name,
                     const std::string& hardware_id, double substep);

  void addSubsteps(int count, double wall_seconds);
  void headPose(const ros::Time& stamp);
  void headPoseMissing();
  void penetrations(int count, double deepest_m);
  void droppedInput(const std::string& what);

  // Levels, as pure functions of the measurements (tested without a master).
  static Level rateLevel(double rate_fraction, const DiagnosticThresholds& t);
  static Level stepLevel(double step_fraction, const DiagnosticThresholds& t);
  static Level tfAgeLevel(bool have_pose, double age, const DiagnosticThresholds& t);
  static Level countLevel(int count, int warn, int error);

 private:
  void onTimer(const ros::TimerEvent& event);

  DiagnosticThresholds thresholds_;
  double substep_;
  diagnostic_updater::Updater updater_;
  ros::Timer timer_;

  std::mutex mutex_;  // the node's callbacks and the publish timer may run on different threads
  ros::Time window_start_;
  long window_substeps_ = 0;
  double window_step_seconds_ = 0.0;
  double window_worst_step_ = 0.0;  ///< worst mean wall time per substep of one update (s)
  bool have_pose_ = false;
  ros::Time pose_stamp_;
  int window_penetrations_ = 0;
  double window_deepest_ = 0.0;
  int window_dropped_ = 0;
  long total_dropped_ = 0;
  std::string last_dropped_;
};

}  // namespace hair_sim
