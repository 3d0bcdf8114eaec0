#pragma once
/// Tessellation of hair strips (uniform B-spline patches, see BSplineSurface) into triangle meshes whose
/// length along the hair equals the strip's hair length (paper, Appendix).
#include <cstddef>
#include <cstdint>
#include <vector>

#include "hair_sim/core/TypeDefs.hpp"

namespace hair_sim {

/// Vertices per span: n_u = (columns - 1) * samples_across + 1, n_v = (rows - 1) * samples_along + 1.
struct LevelOfDetail {
  int samples_across = 2;  ///< samples per span across the width (u), >= 1
  int samples_along = 4;   ///< samples per span along the hair (v), >= 1
};

/// Size of one strip's control grid (for level-of-detail budgeting).
struct StripShape {
  int columns = 2;  ///< control points across the width, >= 2
  int rows = 5;     ///< control points along the hair, >= 4
};

/// Tessellated strip: an n_u x n_v vertex grid, vertex index = iv * n_u + iu, row iv = 0 is the root edge.
struct StripMesh {
  int n_u = 0;
  int n_v = 0;
  std::vector<Vec3> positions;  ///< m, strip frame of the control points
  std::vector<Vec3> normals;    ///< unit, du x dv direction (front face, counter-clockwise triangles)
  std::vector<Vec3> tangents;   ///< unit, along the hair (dv direction), root to tip
  std::vector<float> v_param;   ///< arc length from the root / hair length: 0 at the root, 1 where clipped
  std::vector<float> u_param;   ///< iu / (n_u - 1): 0 on column 0 side, 1 on the last column side

  int vertexCount() const { return n_u * n_v; }
  int index(int iu, int iv) const { return iv * n_u + iu; }
  /// 2 (n_u - 1)(n_v - 1) (one winding).
  std::int64_t triangleCount() const;
};

/// One strip of a batch (Tessellator::tessellate(const StripInput*, ...)).
struct StripInput {
  const Vec3* control_points = nullptr;  ///< columns * rows points, row-major, row 0 at the root
  int columns = 2;
  int rows = 5;
  double hair_length = 0.0;  ///< m, > 0
};

/// How vertices are computed. All three give the same positions within 1e-9 m (in practice ~1e-15) and the
/// same length clipping, normals and tangents.
enum class TessellationMethod {
  /// Paper appendix: per span the control points go to power basis, forward differences in u give the power
  /// basis of the curves along v at each u sample, each curve is followed along v by forward differences
  /// (with the corrected initial differences) accumulating its length, and stops at the hair length.
  ForwardDifferencing,
  /// Every vertex by de Boor's algorithm (BSplineSurface): the reference.
  DeBoor,
  /// Default, the fastest: the uniform B-spline basis values (and derivatives) at the samples of a level of
  /// detail are tabulated once per strip size, with the phantom points folded in, so every vertex is a fixed
  /// small linear combination of control points. Separable: the control columns' curves (and d/dv) at all
  /// v samples first, then (degree + 1) of them are combined per vertex. Exact (no accumulated error).
  /// SIMD: AVX2 (chosen at run time: three or four vertex columns in lanes, one row per step, where they
  /// share their control columns; else four v samples of a column; in the batch form four strips of two
  /// control columns, one per lane) or SSE2 kernels (two v samples at once); bit-identical to each other.
  CachedBasis,
};

/// Turns strip control grids into StripMesh vertex grids.
///
/// Length: every vertex column (fixed u) is followed from the root and the polyline length l is
/// accumulated; the vertex where l would exceed hair_length is moved back along its segment to the exact
/// length (linear interpolation) and all remaining vertices of the column are put at that point
/// (degenerate triangles, fixed vertex count). A curve shorter than hair_length keeps its end (no
/// extrapolation).
///
/// Normals are normalize(dS/du x dS/dv) and tangents normalize(dS/dv) from the analytic derivatives at each
/// sample (forward differences of the derivative curves for ForwardDifferencing); at a clipped vertex the
/// derivatives are interpolated like the position. Degenerate derivatives fall back to deterministic unit
/// vectors.
///
/// Allocation: tessellate() allocates only when the mesh grows beyond its capacity, when a strip size
/// (columns or rows) is seen for the first time at the current level of detail (its basis table is cached) or
/// when its scratch buffers grow for a larger strip. Tessellating strips of one size into a reused StripMesh
/// is allocation-free. Not thread-safe: one instance per thread.
class Tessellator {
 public:
  /// Largest supported samples per span (either direction).
  static constexpr int kMaxSamples = 64;
  /// Highest level offered by selectLevelOfDetail (samples_along).
  static constexpr int kMaxSelectableSamplesAlong = 16;

  /// Throws std::invalid_argument on a bad level of detail.
  explicit Tessellator(const LevelOfDetail& level_of_detail = LevelOfDetail{},
                       TessellationMethod method = TessellationMethod::CachedBasis);

  void setLevelOfDetail(const LevelOfDetail& level_of_detail);
  const LevelOfDetail& levelOfDetail() const { return level_of_detail_; }
  void setMethod(TessellationMethod method) { method_ = method; }
  TessellationMethod method() const { return method_; }

  /// Tessellates one strip: control_points has columns * rows points (row-major, row 0 at the root),
  /// hair_length > 0 (m). Throws std::invalid_argument on null points, columns < 2, rows < 4,
  /// non-positive or non-finite hair length or a non-finite control point.
  void tessellate(const Vec3* control_points, int columns, int rows, double hair_length, StripMesh& mesh);
  /// Same with a size check of the vector.
  void tessellate(const std::vector<Vec3>& control_points, int columns, int rows, double hair_length,
                  StripMesh& mesh);

  /// Tessellates strips[i] into meshes[i] for i < count: the same meshes, bit for bit, as tessellate() one
  /// strip at a time. With CachedBasis on AVX2, four consecutive strips of two control columns and one row
  /// count go through one kernel call, one strip per SIMD lane (at up to 3 samples across; 0.75 x the time
  /// of one call per strip on the default hairstyle, 2026-11-26). Every strip is checked first, as
  /// tessellate() checks one (the message names strip first_index + i): on a bad one it throws
  /// std::invalid_argument and no mesh is changed. Null strips or meshes with count > 0 throw as well.
  void tessellate(const StripInput* strips, std::size_t count, StripMesh* meshes,
                  std::size_t first_index = 0);

  /// Vertex counts for a strip at a level of detail.
  static int verticesAcross(int columns, const LevelOfDetail& level_of_detail);
  static int verticesAlong(int rows, const LevelOfDetail& level_of_detail);
  /// 2 (n_u - 1)(n_v - 1) for one strip / summed over a hairstyle (single-sided: double it when both
  /// windings are rendered). Throws std::invalid_argument on a bad shape or level.
  static std::int64_t triangleCount(const StripShape& shape, const LevelOfDetail& level_of_detail);
  static std::int64_t triangleCount(const std::vector<StripShape>& hairstyle,
                                    const LevelOfDetail& level_of_detail);

  /// Level k of the level-of-detail ladder, k >= 0: samples_along = k + 1,
  /// samples_across = max(1, samples_along / 2), i.e. (1,1), (1,2), (1,3), (2,4) [default], (2,5), (3,6), ...
  /// (samples_along grows first, samples_across follows at half the rate; the triangle count grows strictly
  /// with k). Throws std::invalid_argument when k < 0.
  static LevelOfDetail ladderLevel(int k);
  /// The highest ladder level (up to samples_along = kMaxSelectableSamplesAlong) whose single-sided
  /// triangle count for the hairstyle is <= max_triangles. Throws std::invalid_argument when max_triangles
  /// is not positive, a shape is invalid, or even the minimum level (1, 1) exceeds max_triangles (the
  /// message gives the minimum count). An empty hairstyle gets the highest level.
  static LevelOfDetail selectLevelOfDetail(const std::vector<StripShape>& hairstyle,
                                           std::int64_t max_triangles);

  /// Appends the mesh's triangle list (vertex indices offset by first_vertex) to indices: cell (iu, iv) gives
  /// (iu,iv) (iu+1,iv) (iu,iv+1) and (iu+1,iv) (iu+1,iv+1) (iu,iv+1), counter-clockwise seen from the normal.
  /// With both_windings each triangle is followed by its flipped copy (back face).
  static void appendTriangles(const StripMesh& mesh, std::uint32_t first_vertex, bool both_windings,
                              std::vector<std::uint32_t>& indices);

  /// "ForwardDifferencing", "DeBoor", "CachedBasis".
  static const char* methodName(TessellationMethod method);
  /// The instruction set CachedBasis's kernels run with on this CPU: "AVX2", "SSE2" or "scalar".
  static const char* instructionSet();

 private:
  /// Basis weights of one sample, folded onto `width` consecutive real control points starting at `first`
  /// (the phantom points are linear combinations of real ones). `piece` and `s` locate the sample in its
  /// polynomial piece (used by forward differencing).
  struct BasisSample {
    int first = 0;
    int piece = 0;
    double s = 0.0;
    double weight[4] = {0.0, 0.0, 0.0, 0.0};
    double derivative[4] = {0.0, 0.0, 0.0, 0.0};  ///< d weight / d (u or v), scaled by the span count
  };
  /// The samples in groups of `lanes` consecutive ones (the last sample repeated to fill the last group),
  /// each group on a common window of `window` consecutive control points from first[g]; weights
  /// [g][m][lane].
  struct LaneGroups {
    int lanes = 0;
    int window = 0;
    std::vector<int> first;
    std::vector<double> weight;
    std::vector<double> derivative;
  };
  struct BasisTable {
    int control_count = 0;
    int width = 0;  ///< degree + 1
    std::vector<BasisSample> samples;
    LaneGroups pairs;  ///< SIMD layouts of the samples (along tables only)
    LaneGroups quads;
  };
  /// Per vertex column state of the length walk.
  struct ColumnWalk {
    double length = 0.0;
    bool clipped = false;
    Vec3 position = Vec3::Zero();
    Vec3 d_du = Vec3::Zero();
    Vec3 d_dv = Vec3::Zero();
  };

  /// u_param of an n_u x n_v mesh (built when the grid size changes).
  const std::vector<float>& uParam(int n_u, int n_v);
  const BasisTable& acrossTable(int columns);
  const BasisTable& alongTable(int rows);
  static void buildTable(int control_count, int degree, int samples_per_span, BasisTable& table);
  static void buildLaneGroups(const BasisTable& table, int lanes, LaneGroups& groups);

  /// Length walk of one vertex (ForwardDifferencing, DeBoor): accumulates |step|, clips at hair_length and
  /// stores the position with its raw derivatives (normalised for the whole mesh afterwards).
  static void emitVertex(ColumnWalk& walk, int iu, int iv, const Vec3& position, const Vec3& step,
                         const Vec3& d_du, const Vec3& d_dv, double hair_length, double inverse_length,
                         StripMesh& mesh);

  /// tessellate() after the checks.
  void tessellateChecked(const Vec3* control_points, int columns, int rows, double hair_length,
                         StripMesh& mesh);
  /// CachedBasis (AVX2), four strips of two control columns and one row count, one per lane; meshes
  /// prepared (prepareMesh).
  void tessellateCachedBasisLanes(const StripInput* strips, StripMesh* meshes);

  void tessellateForwardDifferencing(const Vec3* points, int columns, int rows, double hair_length,
                                     StripMesh& mesh);
  void tessellateDeBoor(const Vec3* points, int columns, int rows, double hair_length, StripMesh& mesh);
  void tessellateCachedBasis(const Vec3* points, int columns, int rows, double hair_length, StripMesh& mesh);

  LevelOfDetail level_of_detail_;
  TessellationMethod method_;
  std::vector<BasisTable> across_tables_;
  std::vector<BasisTable> along_tables_;
  std::vector<ColumnWalk> walks_;
  std::vector<double> broadcast_;     ///< CachedBasis (SIMD): control coordinates, each twice
  std::vector<double> curve_;         ///< CachedBasis: control column curves at the v samples
  std::vector<double> curve_dv_;      ///< CachedBasis: their d/dv
  std::vector<double> lane_control_;  ///< CachedBasis (AVX2 batch): four strips' control coordinates in lanes
  std::vector<float> u_param_;        ///< StripMesh::u_param of an n_u x n_v grid (uParam)
  int u_param_n_u_ = 0;
  int u_param_n_v_ = 0;
};

}  // namespace hair_sim
