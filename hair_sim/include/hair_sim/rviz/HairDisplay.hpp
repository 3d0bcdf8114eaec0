#pragma once
/// rviz display of hair_sim's hair (plugin class hair_sim/HairDisplay): subscribes to a
/// hair_sim_msgs/HairState topic (control points, grid size, hair length and colour per strip, about 25 kB
/// per frame) and tessellates every strip in the viewer with the core's Tessellator, drawn as a two-sided
/// mesh with an alpha-mapped hair texture and Kajiya-Kay shading (see HairVisual).
#ifndef Q_MOC_RUN
#include <hair_sim_msgs/HairState.h>
#include <rviz/message_filter_display.h>

#include <memory>
#include <string>

#include "hair_sim/core/TypeDefs.hpp"
#endif

namespace rviz {
class BoolProperty;
class ColorProperty;
class FloatProperty;
class IntProperty;
class StringProperty;
}  // namespace rviz

namespace hair_sim {

class HairVisual;
struct HairVisualStats;

/// Properties (every change applies at once to the last message):
///  - Topic: the HairState topic (default /hair_state).
///  - Level of Detail: ladder level k (Tessellator::ladderLevel: k + 1 samples per span along the hair,
///    max(1, (k + 1) / 2) across; 3 = 2 x 4, the node's default).
///  - Auto Level of Detail, Reference Distance (m): the level follows the camera distance d to the hair,
///    (k + 1) ref / d - 1 rounded (with hysteresis), so the mesh keeps its size on screen.
///  - Texture: the alpha-mapped hair texture; off = plain opaque strips.
///  - Alpha Threshold: texels with a lower alpha are not drawn.
///  - Override Colour, Colour: one colour for every strip instead of each strip's own.
///  - Current Level, Update Time (read only): the level drawn, and the mean wall time per update of
///    tessellation, shading and upload.
class HairDisplay : public rviz::MessageFilterDisplay<hair_sim_msgs::HairState> {
  Q_OBJECT
 public:
  /// Highest ladder level offered.
  static constexpr int kMaxLevel = 15;

  HairDisplay();
  ~HairDisplay() override;

  void reset() override;
  void update(float wall_dt, float ros_dt) override;

 protected:
  void onInitialize() override;
  void processMessage(const hair_sim_msgs::HairState::ConstPtr& msg) override;
  /// As MessageFilterDisplay's, but drops (uncounted) the messages queued before the last reset.
  void processTypeErasedMessage(boost::shared_ptr<const void> msg) override;
  /// As MessageFilterDisplay's, with TCP_NODELAY on the TCP connection (a HairState goes out as soon as it
  /// is written: p99 from tf to receipt 3.2 against 3.6 ms measured with latency_probe).
  void subscribe() override;

 private Q_SLOTS:
  void updateGeometry();
  void updateMaterial();
  void acceptMessages();

 private:
  /// Tessellates, shades and uploads the last message at the current level and view; updates the status.
  void rebuild();
  /// The level the auto level of detail asks for at the current camera distance (hysteresis on `current`).
  int autoLevel(int current) const;
  /// Unit direction from the hair toward the camera, in the message frame.
  Vec3 viewDirection() const;
  /// Asks the master whether the topic is published, and as which type; says so in the Topic status when
  /// nothing publishes it or it carries another type (roscpp only prints that to the console).
  void checkTopic();

  rviz::IntProperty* level_property_;
  rviz::BoolProperty* auto_level_property_;
  rviz::FloatProperty* reference_distance_property_;
  rviz::BoolProperty* texture_property_;
  rviz::FloatProperty* alpha_threshold_property_;
  rviz::BoolProperty* override_colour_property_;
  rviz::ColorProperty* colour_property_;
  rviz::StringProperty* current_level_property_;
  rviz::StringProperty* update_time_property_;

  std::unique_ptr<HairVisual> visual_;
  hair_sim_msgs::HairState::ConstPtr last_msg_;
  bool accepting_ = true;      ///< false from a reset until the messages queued before it are through
  int level_ = 3;              ///< ladder level drawn
  Vec3 view_ = Vec3::UnitX();  ///< view direction of the last rebuild

  /// Sums of update times (s).
  struct UpdateTimes {
    int updates = 0;
    double total = 0.0, tessellate = 0.0, shade = 0.0, upload = 0.0;
    void add(const HairVisualStats& stats);
    /// "0.412 ms (tessellation ..., shading ..., upload ...)": means per update.
    std::string text() const;
  };
  UpdateTimes window_;
  UpdateTimes log_;
  double since_report_ = 0.0;
  double since_message_ = 0.0;      ///< wall time (s) since the last message or subscription
  double since_topic_check_ = 0.0;  ///< wall time (s) since the last checkTopic()
  bool reported_ = false;
};

}  // namespace hair_sim
