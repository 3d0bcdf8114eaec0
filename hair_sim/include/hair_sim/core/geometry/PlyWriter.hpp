#pragma once
/// Export of tessellated strips as a binary little-endian PLY file (Blender, MeshLab).
#include <string>
#include <vector>

#include "hair_sim/core/TypeDefs.hpp"
#include "hair_sim/core/geometry/Tessellator.hpp"

namespace hair_sim {

/// Writes strip meshes with per-vertex colour and alpha as one PLY file:
///   element vertex: float x y z, float nx ny nz, uchar red green blue alpha (0..255, rounded)
///   element face:   list uchar int vertex_indices (triangles)
/// Both faces are visible: every mesh is written twice, the front copy with the mesh normals and the
/// triangles of Tessellator::appendTriangles, the back copy (its own vertices, same positions and colours,
/// negated normals) with the flipped triangles. Hence 2 * sum(n_u n_v) vertices and 2 * sum(triangles)
/// faces; the front vertices of mesh k come first, then its back vertices. Degenerate triangles of
/// clipped tips are kept (the grid stays regular).
class PlyWriter {
 public:
  /// colours: empty (all vertices white, opaque) or one vector per mesh with one Rgba per vertex.
  /// Throws std::invalid_argument on inconsistent sizes and std::runtime_error naming the path and the reason
  /// (strerror) when the file cannot be opened or written (a partly written file is left in place).
  static void write(const std::string& path, const std::vector<StripMesh>& meshes,
                    const std::vector<std::vector<Rgba>>& colours);

  /// Bytes per vertex record (6 floats + 4 uchar) and per triangle record (1 uchar + 3 int32).
  static constexpr int kVertexBytes = 28;
  static constexpr int kFaceBytes = 13;
};

}  // namespace hair_sim
