#pragma once
/// The Ogre side of the rviz display HairDisplay: every strip of a HairState in one Ogre::ManualObject,
/// tessellated by the core's Tessellator, shaded by HairLook and drawn with the alpha-mapped HairTexture.
#include <OgreMaterial.h>
#include <OgreQuaternion.h>
#include <OgreTexture.h>
#include <OgreVector.h>
#include <hair_sim_msgs/HairState.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "hair_sim/core/TypeDefs.hpp"
#include "hair_sim/core/geometry/Tessellator.hpp"

namespace Ogre {
class ManualObject;
class SceneManager;
class SceneNode;
}  // namespace Ogre

namespace hair_sim {

struct HairVisualOptions {
  LevelOfDetail level_of_detail;  ///< samples per span (the node's default 2 x 4)
  bool override_colour = false;   ///< colour instead of every strip's own
  Rgba colour;
  /// Toward the viewer, message frame: the Kajiya-Kay highlight, and the light (from above the viewer).
  Vec3 view_direction{1.0, 0.0, 0.2};
};

/// What the last update() did, and how long each stage took (wall time).
struct HairVisualStats {
  int strips = 0;   ///< drawn
  int skipped = 0;  ///< rejected (bad size, length, point or colour); first_error says why for the first
  std::string first_error;
  /// Good strips left out because drawing them would exceed HairVisual::kMaxVertices; the first's index.
  int over_budget = 0;
  std::size_t first_over_budget = 0;
  int vertices = 0;
  std::int64_t triangles = 0;  ///< drawn (both faces come from one triangle: culling is off)
  double tessellate_seconds = 0.0;
  double shade_seconds = 0.0;
  double upload_seconds = 0.0;
  double totalSeconds() const { return tessellate_seconds + shade_seconds + upload_seconds; }
};

class HairVisual {
 public:
  /// Texture (alpha map) size and strands per tile.
  static constexpr int kTextureWidth = 128;
  static constexpr int kTextureHeight = 256;
  static constexpr int kTextureStrands = 10;
  /// Most vertices drawn for one message (about 100 MB of meshes): the strips after the budget is spent are
  /// left out, so a huge message (1e6 strips, a 1000 x 1000 grid) cannot freeze rviz or exhaust memory. The
  /// default hairstyle takes 5,100 at the default level and 58,500 at the highest.
  static constexpr std::size_t kMaxVertices = 1000000;
  /// Largest control grid accepted (either direction).
  static constexpr std::uint32_t kMaxGrid = 1000;
  /// Largest control point coordinate accepted (m, message frame). Points near FLT_MAX gave vertices that
  /// overflow, and Ogre aborted rviz on the mesh's bounding box.
  static constexpr double kMaxCoordinate = 1e6;

  /// Creates a scene node under parent holding the mesh, and this visual's own material.
  HairVisual(Ogre::SceneManager* scene_manager, Ogre::SceneNode* parent);
  ~HairVisual();
  HairVisual(const HairVisual&) = delete;
  HairVisual& operator=(const HairVisual&) = delete;

  /// Texture on: two passes, both blended with the texture's alpha: texels with alpha >= max(threshold,
  /// 0.5) write depth, the softer ones (alpha >= threshold) are blended over what is drawn without writing
  /// it (so the soft edges of a near strip do not hide the strips behind it). Texture off: one opaque pass,
  /// vertex colours only. Both faces drawn (no culling); lighting comes from the vertices.
  void setMaterial(bool texture, float alpha_threshold);
  /// Rebuilds the mesh from a message (control points in its header frame; the caller places the node).
  HairVisualStats update(const hair_sim_msgs::HairState& msg, const HairVisualOptions& options);
  void clear();
  void setPose(const Ogre::Vector3& position, const Ogre::Quaternion& orientation);
  Ogre::SceneNode* node() const { return node_; }
  /// Mean of the control points of the last update (message frame).
  const Vec3& centre() const { return centre_; }

  /// The strip's colour, or the default hair colour when all four channels are zero (not given).
  static Rgba stripColour(const std_msgs::ColorRGBA& colour);
  /// Whether every channel is in [0, 1] (NaN is not).
  static bool colourValid(const std_msgs::ColorRGBA& colour);
  /// Empty for a valid colour, else why it is not.
  static std::string colourError(const std_msgs::ColorRGBA& colour);
  /// Whether strip `index` shows its texture tile mirrored across (u -> 1 - u): varies the strands.
  static bool mirrored(std::size_t index);

 private:
  static Ogre::TexturePtr hairTexture();

  Ogre::SceneManager* scene_manager_;
  Ogre::SceneNode* node_;
  Ogre::ManualObject* manual_;
  Ogre::MaterialPtr material_;
  Tessellator tessellator_;
  std::vector<StripMesh> meshes_;
  std::vector<std::vector<Rgba>> colours_;
  std::vector<std::size_t> strip_index_;  ///< message index of each mesh
  std::vector<Vec3> points_;
  std::vector<std::uint32_t> indices_;
  Vec3 centre_ = Vec3::Zero();
  std::size_t vertex_capacity_ = 0;
  std::size_t index_capacity_ = 0;
};

}  // namespace hair_sim
