#include "hair_sim/rviz/HairDisplay.hpp"

#include <OgreCamera.h>
#include <OgreSceneNode.h>
#include <ros/master.h>
#include <ros/this_node.h>
#include <rviz/display_context.h>
#include <rviz/frame_manager.h>
#include <rviz/properties/bool_property.h>
#include <rviz/properties/color_property.h>
#include <rviz/properties/float_property.h>
#include <rviz/properties/int_property.h>
#include <rviz/properties/ros_topic_property.h>
#include <rviz/properties/string_property.h>
#include <rviz/view_controller.h>
#include <rviz/view_manager.h>
#include <pluginlib/class_list_macros.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>

#include "hair_sim/rviz/HairVisual.hpp"

namespace hair_sim {

namespace {
/// Printed to the log after this many updates, then every kReportPeriod s.
constexpr int kFirstReportUpdates = 90;
constexpr double kReportPeriod = 60.0;
/// Updates averaged for the Update Time property.
constexpr int kWindow = 30;
/// A rebuild when the view direction turned by more than this (rad): the highlight follows the camera.
constexpr double kViewChange = 0.09;
/// With no message for this long (s), the master is asked whether the topic is published and with which type.
constexpr double kTopicCheckPeriod = 2.0;
}  // namespace

HairDisplay::HairDisplay() {
  level_property_ = new rviz::IntProperty(
      "Level of Detail", 3,
      "Ladder level k of the tessellation: k + 1 samples per B-spline span along the hair, max(1, (k + 1) / "
      "2) "
      "across. 0 = 1 x 1, 3 = 2 x 4 (hair_sim_node's default), 15 = 8 x 16. With Auto Level of Detail: the "
      "level at the Reference Distance.",
      this, SLOT(updateGeometry()));
  level_property_->setMin(0);
  level_property_->setMax(kMaxLevel);
  auto_level_property_ = new rviz::BoolProperty(
      "Auto Level of Detail", false,
      "Choose the level from the camera distance d: (Level of Detail + 1) x Reference Distance / d - 1, so "
      "the mesh keeps about the same size on screen (finer close up, coarser far away).",
      this, SLOT(updateGeometry()));
  auto_level_property_->setDisableChildrenIfFalse(true);
  reference_distance_property_ = new rviz::FloatProperty(
      "Reference Distance", 1.0f, "Camera distance (m) at which the automatic level equals Level of Detail.",
      auto_level_property_, SLOT(updateGeometry()), this);
  reference_distance_property_->setMin(0.01f);
  texture_property_ = new rviz::BoolProperty(
      "Texture", true,
      "Alpha-mapped hair texture: strands with see-through gaps and ragged tips. Off: plain opaque strips.",
      this, SLOT(updateMaterial()));
  alpha_threshold_property_ = new rviz::FloatProperty(
      "Alpha Threshold", 0.05f,
      "Texels of the hair texture with a lower alpha (0..1) are not drawn. Texels above max(threshold, 0.5) "
      "also hide what is behind them in depth.",
      this, SLOT(updateMaterial()));
  alpha_threshold_property_->setMin(0.0f);
  alpha_threshold_property_->setMax(1.0f);
  override_colour_property_ = new rviz::BoolProperty(
      "Override Colour", false, "Draw every strip in Colour instead of the colour in its StripState.", this,
      SLOT(updateGeometry()));
  override_colour_property_->setDisableChildrenIfFalse(true);
  colour_property_ = new rviz::ColorProperty("Colour", QColor(70, 45, 25), "Hair colour (then shaded).",
                                             override_colour_property_, SLOT(updateGeometry()), this);
  current_level_property_ = new rviz::StringProperty(
      "Current Level", "no hair", "Samples across x along per span, triangles drawn.", this);
  current_level_property_->setReadOnly(true);
  update_time_property_ = new rviz::StringProperty(
      "Update Time", "", "Mean wall time per update (tessellation, shading and upload of the mesh).", this);
  update_time_property_->setReadOnly(true);
}

HairDisplay::~HairDisplay() = default;

void HairDisplay::subscribe() {
  if (!isEnabled()) return;
  if (topic_property_->getTopicStd().empty()) {
    sub_.unsubscribe();
    setStatus(rviz::StatusProperty::Error, "Topic", "No topic set");
    return;
  }
  try {
    // Unreliable prefers UDP and falls back to TCP: a publisher without UDPROS (rospy, for one) still
    // connects.
    const ros::TransportHints hints = unreliable_property_->getBool()
                                          ? ros::TransportHints().unreliable().reliable().tcpNoDelay()
                                          : ros::TransportHints().reliable().tcpNoDelay();
    sub_.subscribe(update_nh_, topic_property_->getTopicStd(),
                   static_cast<uint32_t>(queue_size_property_->getInt()), hints);
    setStatus(rviz::StatusProperty::Ok, "Topic", "OK");
  } catch (const ros::Exception& e) {
    setStatus(rviz::StatusProperty::Error, "Topic", QString("Error subscribing: ") + e.what());
  }
  // The master is asked once no message has come for kTopicCheckPeriod.
  since_message_ = 0.0;
  since_topic_check_ = kTopicCheckPeriod;
}

void HairDisplay::checkTopic() {
  std::string topic;
  try {
    topic = update_nh_.resolveName(topic_property_->getTopicStd());
  } catch (const ros::Exception&) {
    return;  // subscribe() has said so
  }
  if (topic.empty() || topic == "/") return;
  // Not ros::master::getTopics: it waits for a master that is gone, and this runs in rviz's GUI thread.
  XmlRpc::XmlRpcValue args, result, payload;
  args[0] = ros::this_node::getName();
  args[1] = "";
  if (!ros::master::execute("getPublishedTopics", args, result, payload, false)) return;
  std::string type;
  for (int i = 0; i < payload.size(); ++i) {
    if (payload[i].size() == 2 && static_cast<std::string>(payload[i][0]) == topic) {
      type = static_cast<std::string>(payload[i][1]);
      break;
    }
  }
  const QString name = QString::fromStdString(topic);
  const std::string wanted = ros::message_traits::datatype<hair_sim_msgs::HairState>();
  if (!type.empty() && type != wanted && type != "*")
    setStatus(rviz::StatusProperty::Error, "Topic",
              QString("%1 is published as %2, not %3")
                  .arg(name, QString::fromStdString(type), QString::fromStdString(wanted)));
  else if (type.empty() && messages_received_ == 0)
    setStatus(rviz::StatusProperty::Warn, "Topic",
              QString("No messages received: nothing publishes %1").arg(name));
  else if (type.empty())
    setStatus(rviz::StatusProperty::Warn, "Topic",
              QString("%1 messages received; nothing publishes %2 now (the hair shown is the last message's)")
                  .arg(messages_received_)
                  .arg(name));
}

void HairDisplay::onInitialize() {
  MFDClass::onInitialize();
  visual_ = std::make_unique<HairVisual>(context_->getSceneManager(), scene_node_);
  if (topic_property_->getTopicStd().empty()) topic_property_->setString("/hair_state");
  updateMaterial();
}

void HairDisplay::reset() {
  MFDClass::reset();
  if (visual_) visual_->clear();
  last_msg_.reset();
  current_level_property_->setStdString("no hair");  // nothing drawn until the next message
  // Messages already handed to Qt's queue (of the previous topic, after a topic change) come before this call
  // in the queue: they are dropped until it runs.
  accepting_ = false;
  QMetaObject::invokeMethod(this, "acceptMessages", Qt::QueuedConnection);
}

void HairDisplay::acceptMessages() { accepting_ = true; }

void HairDisplay::updateMaterial() {
  if (!visual_) return;
  visual_->setMaterial(texture_property_->getBool(), alpha_threshold_property_->getFloat());
  context_->queueRender();
}

void HairDisplay::updateGeometry() {
  if (!visual_) return;
  level_ = auto_level_property_->getBool() ? autoLevel(-100) : level_property_->getInt();
  if (last_msg_) rebuild();
  context_->queueRender();
}

void HairDisplay::processTypeErasedMessage(boost::shared_ptr<const void> msg) {
  // Queued before the last reset (e.g. from the previous topic): dropped before MessageFilterDisplay counts
  // it in the Topic status ("N messages received" of the new topic).
  if (!accepting_) return;
  MFDClass::processTypeErasedMessage(std::move(msg));
}

void HairDisplay::processMessage(const hair_sim_msgs::HairState::ConstPtr& msg) {
  since_message_ = 0.0;
  Ogre::Vector3 position;
  Ogre::Quaternion orientation;
  if (!context_->getFrameManager()->getTransform(msg->header, position, orientation)) {
    setStatus(rviz::StatusProperty::Error, "Transform",
              QString("No transform from '%1' to '%2'")
                  .arg(QString::fromStdString(msg->header.frame_id), fixed_frame_));
    return;
  }
  // No "Transform: OK" of our own: rviz's tf filter keeps a status of its own for this topic, and an OK here
  // stood beside its error for a frame that tf does not know (the messages it drops never get here).
  deleteStatus("Transform");
  visual_->setPose(position, orientation);
  last_msg_ = msg;
  view_ = viewDirection();
  rebuild();
}

Vec3 HairDisplay::viewDirection() const {
  const Ogre::Camera* camera = context_->getViewManager()->getCurrent()->getCamera();
  const Ogre::Vector3 local = visual_->node()->convertWorldToLocalPosition(camera->getDerivedPosition());
  const Vec3 d = Vec3(local.x, local.y, local.z) - visual_->centre();
  return d.norm() > 1e-9 ? Vec3(d / d.norm()) : Vec3::UnitX();
}

int HairDisplay::autoLevel(int current) const {
  const Vec3& c = visual_->centre();
  const Ogre::Vector3 centre = visual_->node()->convertLocalToWorldPosition(
      Ogre::Vector3(static_cast<float>(c.x()), static_cast<float>(c.y()), static_cast<float>(c.z())));
  const Ogre::Camera* camera = context_->getViewManager()->getCurrent()->getCamera();
  const double distance = std::max(1e-3, static_cast<double>(camera->getDerivedPosition().distance(centre)));
  // Clamped before rounding: a huge Reference Distance (up to 3.4e38 m) must give the highest level, not
  // overflow lround.
  const double wanted = std::max(
      0.0,
      std::min(static_cast<double>(kMaxLevel),
               (level_property_->getInt() + 1) * reference_distance_property_->getFloat() / distance - 1.0));
  if (std::abs(wanted - current) < 0.75) return current;  // hysteresis: no flicker at a boundary
  return static_cast<int>(std::lround(wanted));
}

void HairDisplay::update(float wall_dt, float /*ros_dt*/) {
  since_report_ += wall_dt;
  since_message_ += wall_dt;
  since_topic_check_ += wall_dt;
  // While no message comes: does the topic exist, with our type? (A type mismatch is only printed by roscpp.)
  if (isEnabled() && since_message_ >= kTopicCheckPeriod && since_topic_check_ >= kTopicCheckPeriod) {
    since_topic_check_ = 0.0;
    checkTopic();
  }
  if (!last_msg_ || !visual_) return;
  bool changed = false;
  if (auto_level_property_->getBool()) {
    const int level = autoLevel(level_);
    changed = level != level_;
    level_ = level;
  }
  const Vec3 view = viewDirection();
  if (std::acos(std::max(-1.0, std::min(1.0, view.dot(view_)))) > kViewChange) {
    view_ = view;
    changed = true;
  }
  if (changed) {
    rebuild();
    context_->queueRender();
  }
}

void HairDisplay::rebuild() {
  HairVisualOptions options;
  options.level_of_detail = Tessellator::ladderLevel(level_);
  options.override_colour = override_colour_property_->getBool();
  const QColor q = colour_property_->getColor();
  options.colour =
      Rgba{static_cast<float>(q.redF()), static_cast<float>(q.greenF()), static_cast<float>(q.blueF()), 1.0f};
  options.view_direction = view_;
  const HairVisualStats stats = visual_->update(*last_msg_, options);
  if (stats.skipped > 0)
    setStatus(rviz::StatusProperty::Warn, "Strips",
              QString("%1 of %2 strips skipped; %3")
                  .arg(stats.skipped)
                  .arg(last_msg_->strips.size())
                  .arg(QString::fromStdString(stats.first_error)));
  else
    setStatus(rviz::StatusProperty::Ok, "Strips", QString("%1 strips").arg(stats.strips));
  if (stats.over_budget > 0)
    setStatus(
        rviz::StatusProperty::Warn, "Vertices",
        QString("%1 strips not drawn (from strip %2 on): they would take the mesh past %3 vertices at %4 x "
                "%5 samples per span; lower the Level of Detail")
            .arg(stats.over_budget)
            .arg(static_cast<qulonglong>(stats.first_over_budget))
            .arg(static_cast<qulonglong>(HairVisual::kMaxVertices))
            .arg(options.level_of_detail.samples_across)
            .arg(options.level_of_detail.samples_along));
  else
    deleteStatus("Vertices");
  current_level_property_->setStdString(std::to_string(options.level_of_detail.samples_across) + " x " +
                                        std::to_string(options.level_of_detail.samples_along) + ", " +
                                        std::to_string(stats.triangles) + " triangles");
  // The property shows the mean of the last kWindow updates; the log line the mean since the last one.
  window_.add(stats);
  log_.add(stats);
  if (window_.updates >= kWindow) {
    update_time_property_->setStdString(window_.text());
    window_ = UpdateTimes{};
  }
  if ((!reported_ && log_.updates >= kFirstReportUpdates) || (reported_ && since_report_ >= kReportPeriod)) {
    ROS_INFO(
        "hair_sim/HairDisplay: %d strips, level %d x %d, %d vertices, %ld triangles: %s per update, mean of "
        "%d",
        stats.strips, options.level_of_detail.samples_across, options.level_of_detail.samples_along,
        stats.vertices, static_cast<long>(stats.triangles), log_.text().c_str(), log_.updates);
    reported_ = true;
    since_report_ = 0.0;
    log_ = UpdateTimes{};
  }
}

void HairDisplay::UpdateTimes::add(const HairVisualStats& stats) {
  ++updates;
  total += stats.totalSeconds();
  tessellate += stats.tessellate_seconds;
  shade += stats.shade_seconds;
  upload += stats.upload_seconds;
}

std::string HairDisplay::UpdateTimes::text() const {
  const double n = std::max(1, updates);
  char text[160];
  std::snprintf(text, sizeof(text), "%.3f ms (tessellation %.3f, shading %.3f, upload %.3f)", 1e3 * total / n,
                1e3 * tessellate / n, 1e3 * shade / n, 1e3 * upload / n);
  return text;
}

}  // namespace hair_sim

PLUGINLIB_EXPORT_CLASS(hair_sim::HairDisplay, rviz::Display)
