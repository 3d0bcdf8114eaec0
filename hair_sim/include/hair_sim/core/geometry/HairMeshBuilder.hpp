#pragma once
/// From control points to what users see: every strip tessellated at a level of detail (chosen, or
/// derived from a triangle budget), its root edge put on the scalp, and coloured with the hair look.
#include <cstdint>
#include <vector>

#include "hair_sim/core/geometry/HairLook.hpp"
#include "hair_sim/core/geometry/Tessellator.hpp"
#include "hair_sim/core/model/Hairstyle.hpp"

namespace hair_sim {

struct HairMeshOptions {
  LevelOfDetail level_of_detail;   ///< used when max_triangles is 0
  std::int64_t max_triangles = 0;  ///< > 0: the finest ladder level within this single-sided budget
  TessellationMethod method = TessellationMethod::CachedBasis;
  HairLookParameters look;
};

class HairMeshBuilder {
 public:
  /// Throws std::invalid_argument on bad options (e.g. a budget below the coarsest level).
  HairMeshBuilder(const Hairstyle& hairstyle, const HairMeshOptions& options);

  /// Tessellates every strip from control points in one frame (Simulator order: strip by strip,
  /// row-major), with `scalp` expressed in that same frame: the root edge vertices are projected onto
  /// it (the B-spline's root edge is a chord of the scalp between the root control points).
  /// Vertices between control points that the spline carries into one of `bodies` (same frame) are
  /// moved to the body's surface (true closest point): the control points are kept clear of the
  /// bodies by the Simulator, this keeps the drawn surface clear as well.
  void build(const std::vector<Vec3>& points, const std::vector<int>& strip_offsets, const Ellipsoid& scalp,
             const std::vector<Ellipsoid>& bodies = {});
  /// Vertices moved out of a body by the last build().
  int projectedVertices() const { return projected_; }

  const std::vector<StripMesh>& meshes() const { return meshes_; }
  const std::vector<std::vector<Rgba>>& colours() const { return colours_; }
  const LevelOfDetail& levelOfDetail() const { return tessellator_.levelOfDetail(); }
  std::int64_t triangleCount() const;  ///< single-sided, whole hairstyle
  int vertexCount() const;
  /// Deepest mesh vertex inside any of the bodies (m, 0 = none), e.g. the bodies without margin.
  double maxPenetration(const std::vector<Ellipsoid>& bodies) const;

 private:
  const Hairstyle& hairstyle_;
  Tessellator tessellator_;
  HairLook look_;
  std::vector<StripMesh> meshes_;
  std::vector<std::vector<Rgba>> colours_;
  std::vector<Vec3> scratch_;
  std::vector<double> body_reach2_;  ///< per body of the last build(): (largest radius)^2, a little over
  int projected_ = 0;
};

}  // namespace hair_sim
