#include "hair_sim/core/geometry/PlyWriter.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <stdexcept>

namespace hair_sim {

namespace {

void putUint32(std::string& out, std::uint32_t value) {
  for (int byte = 0; byte < 4; ++byte) {
    out.push_back(static_cast<char>((value >> (8 * byte)) & 0xFFU));
  }
}

void putFloat(std::string& out, double value) {
  const float f = static_cast<float>(value);
  std::uint32_t bits = 0;
  std::memcpy(&bits, &f, sizeof(bits));
  putUint32(out, bits);
}

void putChannel(std::string& out, float value) {
  const double clamped = std::max(0.0, std::min(1.0, static_cast<double>(value)));
  out.push_back(static_cast<char>(static_cast<unsigned char>(std::lround(clamped * 255.0))));
}

void putVertex(std::string& out, const Vec3& position, const Vec3& normal, const Rgba& colour) {
  putFloat(out, position.x());
  putFloat(out, position.y());
  putFloat(out, position.z());
  putFloat(out, normal.x());
  putFloat(out, normal.y());
  putFloat(out, normal.z());
  putChannel(out, colour.r);
  putChannel(out, colour.g);
  putChannel(out, colour.b);
  putChannel(out, colour.a);
}

void putTriangle(std::string& out, std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  out.push_back(static_cast<char>(3));
  putUint32(out, a);
  putUint32(out, b);
  putUint32(out, c);
}

}  // namespace

void PlyWriter::write(const std::string& path, const std::vector<StripMesh>& meshes,
                      const std::vector<std::vector<Rgba>>& colours) {
  const char* where = "PlyWriter::write(...) : ";
  if (!colours.empty() && colours.size() != meshes.size()) {
    throw std::invalid_argument(std::string(where) + "colours must be empty or have one entry per mesh (" +
                                std::to_string(meshes.size()) + "), got " + std::to_string(colours.size()));
  }
  std::uint64_t vertex_count = 0;
  std::uint64_t face_count = 0;
  for (std::size_t m = 0; m < meshes.size(); ++m) {
    const StripMesh& mesh = meshes[m];
    const std::size_t count =
        static_cast<std::size_t>(std::max(mesh.n_u, 0)) * static_cast<std::size_t>(std::max(mesh.n_v, 0));
    if (mesh.n_u < 2 || mesh.n_v < 2 || mesh.positions.size() != count || mesh.normals.size() != count) {
      throw std::invalid_argument(std::string(where) + "mesh " + std::to_string(m) + " is " +
                                  std::to_string(mesh.n_u) + " x " + std::to_string(mesh.n_v) + " with " +
                                  std::to_string(mesh.positions.size()) + " positions and " +
                                  std::to_string(mesh.normals.size()) + " normals");
    }
    if (!colours.empty() && colours[m].size() != count) {
      throw std::invalid_argument(std::string(where) + "colours of mesh " + std::to_string(m) +
                                  " must have " + std::to_string(count) + " entries, got " +
                                  std::to_string(colours[m].size()));
    }
    vertex_count += 2 * count;
    face_count += 2 * static_cast<std::uint64_t>(mesh.triangleCount());
  }
  if (vertex_count > static_cast<std::uint64_t>(std::numeric_limits<std::int32_t>::max())) {
    throw std::invalid_argument(std::string(where) +
                                "too many vertices for int indices: " + std::to_string(vertex_count));
  }

  std::string data = "ply\nformat binary_little_endian 1.0\n";
  data += "comment hair_sim strips: " + std::to_string(meshes.size()) +
          ", double-sided (back faces use duplicated vertices with flipped normals)\n";
  data += "element vertex " + std::to_string(vertex_count) + "\n";
  data += "property float x\nproperty float y\nproperty float z\n";
  data += "property float nx\nproperty float ny\nproperty float nz\n";
  data += "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n";
  data += "element face " + std::to_string(face_count) + "\n";
  data += "property list uchar int vertex_indices\nend_header\n";
  data.reserve(data.size() + vertex_count * kVertexBytes + face_count * kFaceBytes);

  const Rgba white{1.f, 1.f, 1.f, 1.f};
  for (std::size_t m = 0; m < meshes.size(); ++m) {
    const StripMesh& mesh = meshes[m];
    for (int side = 0; side < 2; ++side) {
      const double sign = side == 0 ? 1.0 : -1.0;
      for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
        putVertex(data, mesh.positions[i], sign * mesh.normals[i], colours.empty() ? white : colours[m][i]);
      }
    }
  }
  std::vector<std::uint32_t> indices;
  std::uint32_t first = 0;
  for (const StripMesh& mesh : meshes) {
    const auto count = static_cast<std::uint32_t>(mesh.positions.size());
    indices.clear();
    Tessellator::appendTriangles(mesh, first, false, indices);
    for (std::size_t t = 0; t + 2 < indices.size(); t += 3) {
      putTriangle(data, indices[t], indices[t + 1], indices[t + 2]);
    }
    for (std::size_t t = 0; t + 2 < indices.size(); t += 3) {  // back copy, flipped winding
      putTriangle(data, indices[t] + count, indices[t + 2] + count, indices[t + 1] + count);
    }
    first += 2 * count;
  }

  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (!file) {
    throw std::runtime_error(std::string(where) + "cannot open '" + path +
                             "' for writing: " + std::strerror(errno));
  }
  const bool written = std::fwrite(data.data(), 1, data.size(), file) == data.size();
  const int write_error = errno;
  const bool closed = std::fclose(file) == 0;
  if (!written || !closed) {
    throw std::runtime_error(std::string(where) + "failed writing '" + path +
                             "': " + std::strerror(!written ? write_error : errno));
  }
}

}  // namespace hair_sim
