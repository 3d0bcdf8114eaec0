#include "hair_sim/rviz/HairVisual.hpp"

#include <OgreImage.h>
#include <OgreManualObject.h>
#include <OgreMaterialManager.h>
#include <OgrePass.h>
#include <OgreSceneManager.h>
#include <OgreSceneNode.h>
#include <OgreTechnique.h>
#include <OgreTextureManager.h>
#include <OgreTextureUnitState.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "hair_sim/core/geometry/HairLook.hpp"
#include "hair_sim/core/geometry/HairTexture.hpp"
#include "hair_sim/core/model/Strip.hpp"

namespace hair_sim {

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

const char* kTextureName = "hair_sim/HairTexture";
/// The light comes from view direction + this times z (up).
constexpr double kLightElevation = 0.8;

}  // namespace

Ogre::TexturePtr HairVisual::hairTexture() {
  Ogre::TextureManager& manager = Ogre::TextureManager::getSingleton();
  const std::string& group = Ogre::ResourceGroupManager::DEFAULT_RESOURCE_GROUP_NAME;
  Ogre::TexturePtr texture = manager.getByName(kTextureName, group);
  if (texture) return texture;
  // The core's texture: fine strands with mostly transparent gaps, ragged tips, per-strand brightness.
  HairLookParameters look;
  look.strands_per_strip = kTextureStrands;
  look.stripe_contrast = 0.75;
  static const HairTexture pixels(HairLook(look), kTextureWidth, kTextureHeight);
  Ogre::Image image;
  image.loadDynamicImage(const_cast<Ogre::uchar*>(pixels.rgba().data()),
                         static_cast<Ogre::uint32>(pixels.width()),
                         static_cast<Ogre::uint32>(pixels.height()), 1, Ogre::PF_BYTE_RGBA);
  return manager.loadImage(kTextureName, group, image, Ogre::TEX_TYPE_2D, Ogre::MIP_DEFAULT);
}

HairVisual::HairVisual(Ogre::SceneManager* scene_manager, Ogre::SceneNode* parent)
    : scene_manager_(scene_manager) {
  static int count = 0;
  node_ = parent->createChildSceneNode();
  manual_ = scene_manager_->createManualObject();
  manual_->setDynamic(true);
  node_->attachObject(manual_);
  material_ =
      Ogre::MaterialManager::getSingleton().create("hair_sim/HairDisplay/" + std::to_string(count++),
                                                   Ogre::ResourceGroupManager::DEFAULT_RESOURCE_GROUP_NAME);
  setMaterial(true, 0.05f);
}

HairVisual::~HairVisual() {
  node_->detachAllObjects();
  scene_manager_->destroyManualObject(manual_);
  scene_manager_->destroySceneNode(node_);
  Ogre::MaterialManager::getSingleton().remove(material_);
}

void HairVisual::setMaterial(bool texture, float alpha_threshold) {
  const float threshold = std::max(0.0f, std::min(1.0f, alpha_threshold));
  Ogre::Technique* technique = material_->getTechnique(0);
  technique->removeAllPasses();
  auto make_pass = [&](bool blended, bool depth_write, unsigned char reject_below) {
    Ogre::Pass* pass = technique->createPass();
    pass->setLightingEnabled(false);  // Kajiya-Kay shading is in the vertex colours
    pass->setCullingMode(Ogre::CULL_NONE);
    pass->setManualCullingMode(Ogre::MANUAL_CULL_NONE);
    pass->setDepthWriteEnabled(depth_write);
    if (blended) {
      pass->setSceneBlending(Ogre::SBT_TRANSPARENT_ALPHA);
      // Fragments below the threshold are dropped (alpha 0 always: nothing to draw).
      if (reject_below > 0)
        pass->setAlphaRejectSettings(Ogre::CMPF_GREATER_EQUAL, reject_below);
      else
        pass->setAlphaRejectSettings(Ogre::CMPF_GREATER, 0);
      Ogre::TextureUnitState* unit = pass->createTextureUnitState();
      unit->setTexture(hairTexture());
      unit->setTextureAddressingMode(Ogre::TextureUnitState::TAM_CLAMP);
      unit->setTextureFiltering(Ogre::TFO_TRILINEAR);
    }
    return pass;
  };
  if (texture) {
    const auto to_byte = [](float a) { return static_cast<unsigned char>(std::lround(255.0f * a)); };
    make_pass(true, true, to_byte(std::max(threshold, 0.5f)));
    Ogre::Pass* soft = make_pass(true, false, to_byte(threshold));
    soft->setDepthFunction(Ogre::CMPF_LESS);  // not again over the dense texels drawn by the first pass
  } else {
    make_pass(false, true, 0);
  }
  material_->load();
}

Rgba HairVisual::stripColour(const std_msgs::ColorRGBA& c) {
  if (c.r == 0.0f && c.g == 0.0f && c.b == 0.0f && c.a == 0.0f) return Strip{}.color;
  return Rgba{c.r, c.g, c.b, c.a};
}

bool HairVisual::colourValid(const std_msgs::ColorRGBA& c) {
  // Written so that NaN fails.
  const auto in_range = [](float v) { return v >= 0.0f && v <= 1.0f; };
  return in_range(c.r) && in_range(c.g) && in_range(c.b) && in_range(c.a);
}

std::string HairVisual::colourError(const std_msgs::ColorRGBA& c) {
  if (colourValid(c)) return "";
  char text[160];
  std::snprintf(text, sizeof(text), "colour (%g, %g, %g, %g) has a channel outside [0, 1]", c.r, c.g, c.b,
                c.a);
  return text;
}

bool HairVisual::mirrored(std::size_t index) { return ((index * 2654435761U) >> 7) & 1U; }

void HairVisual::setPose(const Ogre::Vector3& position, const Ogre::Quaternion& orientation) {
  node_->setPosition(position);
  node_->setOrientation(orientation);
}

void HairVisual::clear() {
  manual_->clear();
  vertex_capacity_ = index_capacity_ = 0;
}

HairVisualStats HairVisual::update(const hair_sim_msgs::HairState& msg, const HairVisualOptions& options) {
  HairVisualStats stats;
  // 1. Tessellation (the core's Tessellator, the same code as the node's markers).
  Clock::time_point start = Clock::now();
  if (tessellator_.levelOfDetail().samples_across != options.level_of_detail.samples_across ||
      tessellator_.levelOfDetail().samples_along != options.level_of_detail.samples_along)
    tessellator_.setLevelOfDetail(options.level_of_detail);
  strip_index_.clear();
  Vec3 sum = Vec3::Zero();
  std::size_t point_count = 0;
  std::size_t vertex_total = 0;
  // Skips strip s; why() (called for the first skipped strip only) says why.
  const auto skip = [&stats](std::size_t s, const auto& why) {
    if (stats.skipped++ == 0) stats.first_error = "strip " + std::to_string(s) + ": " + why();
  };
  for (std::size_t s = 0; s < msg.strips.size(); ++s) {
    const hair_sim_msgs::StripState& strip = msg.strips[s];
    // Cheap checks first (a hostile message may hold a million strips), the tessellator's own after.
    if (strip.columns > kMaxGrid || strip.rows > kMaxGrid) {
      skip(s, [&] {
        return "grid " + std::to_string(strip.columns) + " x " + std::to_string(strip.rows) +
               " is larger than " + std::to_string(kMaxGrid) + " x " + std::to_string(kMaxGrid);
      });
      continue;
    }
    if (strip.xyz.size() != 3 * static_cast<std::size_t>(strip.columns) * strip.rows) {
      skip(s, [&] {
        return std::to_string(strip.xyz.size()) + " xyz values for a " + std::to_string(strip.columns) +
               " x " + std::to_string(strip.rows) + " grid (3 per point)";
      });
      continue;
    }
    if (!colourValid(strip.color)) {
      skip(s, [&] { return colourError(strip.color); });
      continue;
    }
    if (strip.columns >= 2 && strip.rows >= 4) {  // else the tessellator says what is wrong
      const std::size_t vertices = static_cast<std::size_t>(Tessellator::verticesAcross(
                                       static_cast<int>(strip.columns), options.level_of_detail)) *
                                   static_cast<std::size_t>(Tessellator::verticesAlong(
                                       static_cast<int>(strip.rows), options.level_of_detail));
      if (vertex_total + vertices > kMaxVertices) {
        if (stats.over_budget++ == 0) stats.first_over_budget = s;
        continue;
      }
    }
    const std::size_t n_points = strip.xyz.size() / 3;
    points_.resize(n_points);
    std::size_t far_point = n_points;  // the first beyond kMaxCoordinate (NaN is the tessellator's to name)
    for (std::size_t k = 0; k < n_points; ++k) {
      points_[k] = Vec3(strip.xyz[3 * k], strip.xyz[3 * k + 1], strip.xyz[3 * k + 2]);
      if (far_point == n_points && points_[k].cwiseAbs().maxCoeff() > kMaxCoordinate) far_point = k;
    }
    if (far_point < n_points) {
      skip(s, [&] {
        const Vec3& p = points_[far_point];
        char text[200];
        std::snprintf(text, sizeof(text), "control point %zu (%g, %g, %g) is more than %g m from the origin",
                      far_point, p.x(), p.y(), p.z(), kMaxCoordinate);
        return std::string(text);
      });
      continue;
    }
    // Meshes grow with the strips drawn only (at most kMaxVertices / 8 of them), not with the message.
    if (meshes_.size() <= strip_index_.size()) {
      meshes_.resize(strip_index_.size() + 1);
      colours_.resize(strip_index_.size() + 1);
    }
    StripMesh& mesh = meshes_[strip_index_.size()];
    try {
      tessellator_.tessellate(points_, static_cast<int>(strip.columns), static_cast<int>(strip.rows),
                              strip.hair_length, mesh);
    } catch (const std::exception& e) {
      skip(s, [&e] { return std::string(e.what()); });
      continue;
    }
    // Ogre aborts rviz on a bounding box with a NaN corner: no vertex that is not finite reaches it.
    if (!std::all_of(mesh.positions.begin(), mesh.positions.end(),
                     [](const Vec3& p) { return p.allFinite(); })) {
      skip(s, [] { return std::string("tessellation gave a vertex that is not finite"); });
      continue;
    }
    vertex_total += static_cast<std::size_t>(mesh.vertexCount());
    for (const Vec3& p : points_) sum += p;
    point_count += points_.size();
    strip_index_.push_back(s);
  }
  if (point_count > 0) centre_ = sum / static_cast<double>(point_count);
  stats.strips = static_cast<int>(strip_index_.size());
  stats.tessellate_seconds = secondsSince(start);

  // 2. Shading (the core's HairLook: Kajiya-Kay from the tangents, darker roots; the texture adds the rest).
  start = Clock::now();
  HairLookParameters look_parameters;
  look_parameters.view_direction = options.view_direction;
  // A key light above the viewer (z up in the message frame), so the highlight shows from every side.
  look_parameters.light_direction = options.view_direction + Vec3(0.0, 0.0, kLightElevation);
  const HairLook look(look_parameters);
  for (std::size_t m = 0; m < strip_index_.size(); ++m) {
    const Rgba base =
        options.override_colour ? options.colour : stripColour(msg.strips[strip_index_[m]].color);
    look.shade(meshes_[m], base, colours_[m]);
  }
  stats.shade_seconds = secondsSince(start);

  // 3. Upload: position, colour, texture coordinates (u across, mirrored for every other strip; v = arc
  // length / hair length), one winding (culling is off).
  start = Clock::now();
  std::size_t vertex_count = 0, index_count = 0;
  for (std::size_t m = 0; m < strip_index_.size(); ++m) {
    vertex_count += static_cast<std::size_t>(meshes_[m].vertexCount());
    index_count += static_cast<std::size_t>(3 * meshes_[m].triangleCount());
  }
  if (vertex_count == 0) {
    clear();
  } else {
    const std::string& group = Ogre::ResourceGroupManager::DEFAULT_RESOURCE_GROUP_NAME;
    if (manual_->getSections().empty() || vertex_count > vertex_capacity_ || index_count > index_capacity_ ||
        vertex_count * 2 < vertex_capacity_) {
      manual_->clear();
      manual_->estimateVertexCount(vertex_count);
      manual_->estimateIndexCount(index_count);
      manual_->begin(material_->getName(), Ogre::RenderOperation::OT_TRIANGLE_LIST, group);
      vertex_capacity_ = vertex_count;
      index_capacity_ = index_count;
    } else {
      manual_->beginUpdate(0);
    }
    std::uint32_t first = 0;
    for (std::size_t m = 0; m < strip_index_.size(); ++m) {
      const StripMesh& mesh = meshes_[m];
      const std::vector<Rgba>& colours = colours_[m];
      const bool mirror = mirrored(strip_index_[m]);
      for (std::size_t k = 0; k < mesh.positions.size(); ++k) {
        const Vec3& p = mesh.positions[k];
        const Rgba& c = colours[k];
        manual_->position(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
        manual_->colour(c.r, c.g, c.b, c.a);
        manual_->textureCoord(mirror ? 1.0f - mesh.u_param[k] : mesh.u_param[k], mesh.v_param[k]);
      }
      indices_.clear();
      Tessellator::appendTriangles(mesh, first, false, indices_);
      for (std::uint32_t i : indices_) manual_->index(i);
      first += static_cast<std::uint32_t>(mesh.vertexCount());
    }
    manual_->end();
  }
  stats.vertices = static_cast<int>(vertex_count);
  stats.triangles = static_cast<std::int64_t>(index_count / 3);
  stats.upload_seconds = secondsSince(start);
  return stats;
}

}  // namespace hair_sim
