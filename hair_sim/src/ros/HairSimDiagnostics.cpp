#include "hair_sim/ros/HairSimDiagnostics.hpp"

#include <cmath>
#include <stdexcept>
#include <type_traits>

#include "hair_sim/core/util/YamlReader.hpp"

namespace hair_sim {

namespace {

using Status = diagnostic_msgs::DiagnosticStatus;

template <typename T>
void readOne(const ros::NodeHandle& nh, const std::string& name, T& value) {
  if (!nh.hasParam(name)) return;
  if (!nh.getParam(name, value))
    throw std::invalid_argument("parameter ~" + name + ": is not " +
                                (std::is_same<T, int>::value ? "an integer" : "a number"));
}

void requireOrdered(const std::string& warn, double w, const std::string& error, double e, bool ascending) {
  const bool ok = std::isfinite(w) && std::isfinite(e) && w >= 0.0 && (ascending ? w <= e : w >= e);
  if (!ok)
    throw std::invalid_argument("parameters ~" + warn + " (" + formatDouble(w) + ") and ~" + error + " (" +
                                formatDouble(e) + "): need 0 <= " + (ascending ? warn : error) +
                                " <= " + (ascending ? error : warn));
}

}  // namespace

DiagnosticThresholds DiagnosticThresholds::read(const ros::NodeHandle& nh) {
  DiagnosticThresholds t;
  readOne(nh, "diag_rate_warn", t.rate_warn);
  readOne(nh, "diag_rate_error", t.rate_error);
  readOne(nh, "diag_step_warn", t.step_warn);
  readOne(nh, "diag_step_error", t.step_error);
  readOne(nh, "diag_tf_age_warn", t.tf_age_warn);
  readOne(nh, "diag_tf_age_error", t.tf_age_error);
  readOne(nh, "diag_penetration_warn", t.penetration_warn);
  readOne(nh, "diag_penetration_error", t.penetration_error);
  readOne(nh, "diag_dropped_warn", t.dropped_warn);
  readOne(nh, "diag_dropped_error", t.dropped_error);
  requireOrdered("diag_rate_warn", t.rate_warn, "diag_rate_error", t.rate_error, false);
  requireOrdered("diag_step_warn", t.step_warn, "diag_step_error", t.step_error, true);
  requireOrdered("diag_tf_age_warn", t.tf_age_warn, "diag_tf_age_error", t.tf_age_error, true);
  requireOrdered("diag_penetration_warn", t.penetration_warn, "diag_penetration_error", t.penetration_error,
                 true);
  requireOrdered("diag_dropped_warn", t.dropped_warn, "diag_dropped_error", t.dropped_error, true);
  return t;
}

HairSimDiagnostics::HairSimDiagnostics(ros::NodeHandle nh, ros::NodeHandle private_nh,
                                       const std::string& name, const std::string& hardware_id,
                                       double substep)
    : thresholds_(DiagnosticThresholds::read(private_nh)), substep_(substep), updater_(nh, private_nh, name) {
  updater_.setHardwareID(hardware_id);
  const double target = 1.0 / substep_;
  updater_.add("simulated rate", [this, target](diagnostic_updater::DiagnosticStatusWrapper& s) {
    const double seconds = (ros::Time::now() - window_start_).toSec();
    const double rate = seconds > 0.0 ? window_substeps_ / seconds : 0.0;
    const Level level = rateLevel(rate / target, thresholds_);
    s.summaryf(level, "%.0f substeps/s of %.0f (%.0f %%)%s", rate, target, 100.0 * rate / target,
               have_pose_ ? "" : ": no head pose");
    s.add("simulated substeps per second", rate);
    s.add("target substeps per second", target);
    s.add("substeps in window", window_substeps_);
  });
  updater_.add("step time", [this](diagnostic_updater::DiagnosticStatusWrapper& s) {
    const double mean = window_substeps_ > 0 ? window_step_seconds_ / window_substeps_ : 0.0;
    const Level level = stepLevel(std::max(mean, window_worst_step_) / substep_, thresholds_);
    s.summaryf(level, "%.3f ms per substep (budget %.3f ms)", 1e3 * mean, 1e3 * substep_);
    s.add("mean ms per substep", 1e3 * mean);
    s.add("worst update, ms per substep", 1e3 * window_worst_step_);
    s.add("substep ms", 1e3 * substep_);
  });
  updater_.add("head tf", [this](diagnostic_updater::DiagnosticStatusWrapper& s) {
    const double age = have_pose_ ? (ros::Time::now() - pose_stamp_).toSec() : -1.0;
    const Level level = tfAgeLevel(have_pose_, age, thresholds_);
    if (have_pose_)
      s.summaryf(level, "newest head pose %.3f s old", age);
    else
      s.summary(level, "no head pose in tf (is something broadcasting the head frame?)");
    s.add("tf age s", age);
  });
  updater_.add("penetration", [this](diagnostic_updater::DiagnosticStatusWrapper& s) {
    const Level level =
        countLevel(window_penetrations_, thresholds_.penetration_warn, thresholds_.penetration_error);
    s.summaryf(level, "%d control points inside a body (deepest %.4f m)", window_penetrations_,
               window_deepest_);
    s.add("control points inside a body", window_penetrations_);
    s.add("deepest m", window_deepest_);
  });
  updater_.add("inputs", [this](diagnostic_updater::DiagnosticStatusWrapper& s) {
    const Level level = countLevel(window_dropped_, thresholds_.dropped_warn, thresholds_.dropped_error);
    if (window_dropped_ > 0)
      s.summaryf(level, "%d inputs dropped (last: %s)", window_dropped_, last_dropped_.c_str());
    else
      s.summary(level, "no input dropped");
    s.add("dropped in window", window_dropped_);
    s.add("dropped since start", total_dropped_);
    s.add("last dropped", last_dropped_);
  });
  window_start_ = ros::Time::now();
  timer_ = nh.createTimer(ros::Duration(updater_.getPeriod()), &HairSimDiagnostics::onTimer, this);
}

void HairSimDiagnostics::onTimer(const ros::TimerEvent&) {
  std::lock_guard<std::mutex> lock(mutex_);
  updater_.force_update();
  window_start_ = ros::Time::now();
  window_substeps_ = 0;
  window_step_seconds_ = 0.0;
  window_worst_step_ = 0.0;
  window_penetrations_ = 0;
  window_deepest_ = 0.0;
  window_dropped_ = 0;
}

void HairSimDiagnostics::addSubsteps(int count, double wall_seconds) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (count <= 0) return;
  window_substeps_ += count;
  window_step_seconds_ += wall_seconds;
  window_worst_step_ = std::max(window_worst_step_, wall_seconds / count);
}

void HairSimDiagnostics::headPose(const ros::Time& stamp) {
  std::lock_guard<std::mutex> lock(mutex_);
  have_pose_ = true;
  pose_stamp_ = stamp;
}

void HairSimDiagnostics::headPoseMissing() {
  std::lock_guard<std::mutex> lock(mutex_);
  have_pose_ = false;
}

void HairSimDiagnostics::penetrations(int count, double deepest_m) {
  std::lock_guard<std::mutex> lock(mutex_);
  window_penetrations_ = std::max(window_penetrations_, count);
  window_deepest_ = std::max(window_deepest_, deepest_m);
}

void HairSimDiagnostics::droppedInput(const std::string& what) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++window_dropped_;
  ++total_dropped_;
  last_dropped_ = what;
}

HairSimDiagnostics::Level HairSimDiagnostics::rateLevel(double fraction, const DiagnosticThresholds& t) {
  if (!(fraction >= t.rate_error)) return Status::ERROR;
  if (fraction < t.rate_warn) return Status::WARN;
  return Status::OK;
}

HairSimDiagnostics::Level HairSimDiagnostics::stepLevel(double fraction, const DiagnosticThresholds& t) {
  if (!(fraction <= t.step_error)) return Status::ERROR;
  if (fraction > t.step_warn) return Status::WARN;
  return Status::OK;
}

HairSimDiagnostics::Level HairSimDiagnostics::tfAgeLevel(bool have_pose, double age,
                                                         const DiagnosticThresholds& t) {
  if (!have_pose || !(age <= t.tf_age_error)) return Status::ERROR;
  if (age > t.tf_age_warn) return Status::WARN;
  return Status::OK;
}

HairSimDiagnostics::Level HairSimDiagnostics::countLevel(int count, int warn, int error) {
  if (count >= error) return Status::ERROR;
  if (count >= warn) return Status::WARN;
  return Status::OK;
}

}  // namespace hair_sim
