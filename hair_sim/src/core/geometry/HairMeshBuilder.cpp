#include "hair_sim/core/geometry/HairMeshBuilder.hpp"

#include <algorithm>
#include <stdexcept>

namespace hair_sim {

namespace {
LevelOfDetail chooseLevel(const Hairstyle& style, const HairMeshOptions& o) {
  if (o.max_triangles <= 0) return o.level_of_detail;
  std::vector<StripShape> shapes;
  for (const Strip& s : style.strips) shapes.push_back(StripShape{s.columns, s.rows});
  return Tessellator::selectLevelOfDetail(shapes, o.max_triangles);
}
}  // namespace

HairMeshBuilder::HairMeshBuilder(const Hairstyle& hairstyle, const HairMeshOptions& options)
    : hairstyle_(hairstyle),
      tessellator_(chooseLevel(hairstyle, options), options.method),
      look_(options.look) {
  meshes_.resize(hairstyle_.strips.size());
  colours_.resize(hairstyle_.strips.size());
}

void HairMeshBuilder::build(const std::vector<Vec3>& points, const std::vector<int>& strip_offsets,
                            const Ellipsoid& scalp, const std::vector<Ellipsoid>& bodies) {
  projected_ = 0;
  if (strip_offsets.size() != hairstyle_.strips.size())
    throw std::invalid_argument("HairMeshBuilder::build(...) : " + std::to_string(strip_offsets.size()) +
                                " strip offsets for " + std::to_string(hairstyle_.strips.size()) + " strips");
  // A vertex farther from a body's centre than its largest radius (with 1e-9 to spare) is outside it: the
  // exact test (a transform into the body's sphere space) only for the others.
  body_reach2_.clear();
  for (const Ellipsoid& e : bodies) {
    const double reach = e.radii().maxCoeff() * (1.0 + 1e-9);
    body_reach2_.push_back(reach * reach);
  }
  for (std::size_t s = 0; s < hairstyle_.strips.size(); ++s) {
    const Strip& strip = hairstyle_.strips[s];
    const std::size_t first = static_cast<std::size_t>(strip_offsets[s]);
    if (first + static_cast<std::size_t>(strip.pointCount()) > points.size())
      throw std::invalid_argument("HairMeshBuilder::build(...) : too few points for strip " +
                                  std::to_string(s));
    StripMesh& mesh = meshes_[s];
    tessellator_.tessellate(points.data() + first, strip.columns, strip.rows, strip.hair_length, mesh);
    for (int iu = 0; iu < mesh.n_u; ++iu) {
      Vec3& p = mesh.positions[static_cast<std::size_t>(mesh.index(iu, 0))];
      p = scalp.radialProjection(p);
    }
    for (std::size_t k = static_cast<std::size_t>(mesh.n_u); k < mesh.positions.size(); ++k) {
      Vec3& p = mesh.positions[k];
      for (std::size_t b = 0; b < bodies.size(); ++b) {
        const Ellipsoid& e = bodies[b];
        if ((p - e.center()).squaredNorm() > body_reach2_[b] || e.implicitValue(p) >= 0.0) continue;
        const Ellipsoid::ClosestPoint cp = e.closestPoint(p);
        p = cp.point + 1e-6 * cp.normal;
        ++projected_;
      }
    }
    look_.colorize(mesh, strip.color, static_cast<std::uint32_t>(s * 2654435761u), colours_[s]);
  }
}

std::int64_t HairMeshBuilder::triangleCount() const {
  std::int64_t n = 0;
  for (const StripMesh& m : meshes_) n += m.triangleCount();
  return n;
}

int HairMeshBuilder::vertexCount() const {
  int n = 0;
  for (const StripMesh& m : meshes_) n += m.vertexCount();
  return n;
}

double HairMeshBuilder::maxPenetration(const std::vector<Ellipsoid>& bodies) const {
  double worst = 0.0;
  for (const StripMesh& m : meshes_)
    for (const Vec3& p : m.positions)
      for (const Ellipsoid& e : bodies)
        if (e.implicitValue(p) < -1e-12) worst = std::max(worst, -e.closestPoint(p).signed_distance);
  return worst;
}

}  // namespace hair_sim
