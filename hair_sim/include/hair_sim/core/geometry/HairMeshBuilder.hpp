#pragma once
/// From control points to what users see: every strip tessellated at a level of detail (chosen, or
/// derived from a triangle budget), its root edge put on the scalp, and coloured with the hair look.
#include <cstdint>
#include <exception>
#include <memory>
#include <vector>

#include "hair_sim/core/geometry/HairLook.hpp"
#include "hair_sim/core/geometry/Tessellator.hpp"
#include "hair_sim/core/model/Hairstyle.hpp"

namespace hair_sim {

class LaneWorkers;

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
  /// The strips' grids, as the tessellator's level-of-detail functions take them.
  static std::vector<StripShape> stripShapes(const Hairstyle& hairstyle);
  /// The triangles of the coarsest level (1 x 1 samples per span): the least a max_triangles budget can be.
  static std::int64_t minimumTriangles(const Hairstyle& hairstyle);
  ~HairMeshBuilder();

  /// Threads that build() uses (1 = the calling thread alone, the default): the strips go in blocks of
  /// kStripsPerBlock to the calling thread and threads - 1 helpers, each block with its own tessellator;
  /// the meshes are the same bit for bit with any count. Hairstyles of fewer than kMinStripsForHelpers
  /// strips stay on the calling thread (at 100 strips the mesh took 1.7 x less wall time with 2 threads
  /// alone, but hair_sim_node's markers came later and cost more CPU on a busy 2-core host). Throws
  /// std::invalid_argument outside [1, 64].
  void setThreads(int threads);
  int threads() const;
  static constexpr int kMinStripsForHelpers = 256;
  static constexpr int kStripsPerBlock = 16;

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
  const LevelOfDetail& levelOfDetail() const { return level_of_detail_; }
  std::int64_t triangleCount() const;  ///< single-sided, whole hairstyle
  int vertexCount() const;
  /// Deepest mesh vertex inside any of the bodies (m, 0 = none), e.g. the bodies without margin.
  double maxPenetration(const std::vector<Ellipsoid>& bodies) const;

 private:
  /// The strips [first, last) of one build(): tessellated, put on the scalp, out of the bodies, coloured.
  void buildStrips(std::size_t first, std::size_t last, Tessellator& tessellator, int& projected);
  static void buildBlock(void* context, std::size_t block);

  const Hairstyle& hairstyle_;
  LevelOfDetail level_of_detail_;
  HairLook look_;
  std::vector<Tessellator> tessellators_;  ///< one per block of strips (Tessellator is not thread-safe)
  std::vector<int> block_projected_;       ///< per block: vertices moved out of a body
  std::vector<std::exception_ptr> block_errors_;  ///< per block: what its strips threw (rethrown by build())
  std::vector<StripMesh> meshes_;
  std::vector<std::vector<Rgba>> colours_;
  std::vector<std::vector<double>> profiles_;  ///< per strip: HairLook::stripeProfiles (computed once)
  std::vector<double> body_reach2_;  ///< per body of the last build(): (largest radius)^2, a little over
  int projected_ = 0;
  std::unique_ptr<LaneWorkers> workers_;  ///< the helper threads (setThreads), or none
  /// The arguments of the build() under way, for the blocks.
  const std::vector<Vec3>* points_ = nullptr;
  const std::vector<int>* strip_offsets_ = nullptr;
  const Ellipsoid* scalp_ = nullptr;
  const std::vector<Ellipsoid>* bodies_ = nullptr;
};

}  // namespace hair_sim
