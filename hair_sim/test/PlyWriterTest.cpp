#include "hair_sim/core/geometry/PlyWriter.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "TestUtil.hpp"

#include "hair_sim/core/geometry/Tessellator.hpp"

namespace hair_sim {
namespace {

/// A 2 x 4 strip at level (1, 1): 2 x 4 vertices, 6 triangles.
StripMesh smallMesh(double offset) {
  std::vector<Vec3> grid(8);
  for (int r = 0; r < 4; ++r) {
    grid[static_cast<std::size_t>(2 * r)] = Vec3(offset, 0.0, -0.1 * r);
    grid[static_cast<std::size_t>(2 * r + 1)] = Vec3(offset, 0.02, -0.1 * r);
  }
  Tessellator tessellator(LevelOfDetail{1, 1});
  StripMesh mesh;
  tessellator.tessellate(grid, 2, 4, 1.0, mesh);
  return mesh;
}

struct PlyFile {
  std::vector<std::string> header;
  std::string payload;
};

PlyFile readPly(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  EXPECT_TRUE(file.good()) << path;
  const std::string data((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  const std::string end = "end_header\n";
  const std::size_t stop = data.find(end);
  EXPECT_NE(stop, std::string::npos);
  PlyFile ply;
  std::istringstream lines(data.substr(0, stop + end.size()));
  for (std::string line; std::getline(lines, line);) {
    ply.header.push_back(line);
  }
  ply.payload = data.substr(stop + end.size());
  return ply;
}

float floatAt(const std::string& payload, std::size_t offset) {
  std::uint32_t bits = 0;
  for (int b = 3; b >= 0; --b) {  // little endian
    bits = (bits << 8) | static_cast<unsigned char>(payload[offset + static_cast<std::size_t>(b)]);
  }
  float value = 0.f;
  std::memcpy(&value, &bits, sizeof(value));
  return value;
}

std::int32_t intAt(const std::string& payload, std::size_t offset) {
  std::uint32_t bits = 0;
  for (int b = 3; b >= 0; --b) {
    bits = (bits << 8) | static_cast<unsigned char>(payload[offset + static_cast<std::size_t>(b)]);
  }
  return static_cast<std::int32_t>(bits);
}

unsigned byteAt(const std::string& payload, std::size_t offset) {
  return static_cast<unsigned char>(payload[offset]);
}

TEST(PlyWriterTest, WritesHeaderVerticesAndBothWindings) {
  const std::vector<StripMesh> meshes = {smallMesh(0.0), smallMesh(0.5)};
  std::vector<std::vector<Rgba>> colours(2, std::vector<Rgba>(8, Rgba{0.5f, 1.0f, 0.0f, 0.25f}));
  colours[1][3] = Rgba{1.0f, 0.0f, 2.0f, -1.0f};  // clamped on output
  const std::string path = test::tempPath("ply_writer_test.ply");
  PlyWriter::write(path, meshes, colours);

  const PlyFile ply = readPly(path);
  const std::vector<std::string> expected = {"ply",
                                             "format binary_little_endian 1.0",
                                             "element vertex 32",
                                             "property float x",
                                             "property float y",
                                             "property float z",
                                             "property float nx",
                                             "property float ny",
                                             "property float nz",
                                             "property uchar red",
                                             "property uchar green",
                                             "property uchar blue",
                                             "property uchar alpha",
                                             "element face 24",
                                             "property list uchar int vertex_indices",
                                             "end_header"};
  std::vector<std::string> without_comments;
  for (const std::string& line : ply.header) {
    if (line.rfind("comment", 0) != 0) {
      without_comments.push_back(line);
    }
  }
  EXPECT_EQ(without_comments, expected);
  // 2 meshes x 2 sides x 8 vertices x 28 bytes + 2 x 2 x 6 triangles x 13 bytes.
  ASSERT_EQ(ply.payload.size(), 32u * 28u + 24u * 13u);

  // Vertex 1 of mesh 0: (0, 0.02, 0), normal of the front side, colour (128, 255, 0, 64).
  const std::size_t v1 = 28;
  EXPECT_FLOAT_EQ(floatAt(ply.payload, v1 + 0), 0.0f);
  EXPECT_FLOAT_EQ(floatAt(ply.payload, v1 + 4), 0.02f);
  EXPECT_FLOAT_EQ(floatAt(ply.payload, v1 + 8), 0.0f);
  const Vec3& n = meshes[0].normals[1];
  EXPECT_FLOAT_EQ(floatAt(ply.payload, v1 + 12), static_cast<float>(n.x()));
  EXPECT_FLOAT_EQ(floatAt(ply.payload, v1 + 16), static_cast<float>(n.y()));
  EXPECT_FLOAT_EQ(floatAt(ply.payload, v1 + 20), static_cast<float>(n.z()));
  EXPECT_EQ(byteAt(ply.payload, v1 + 24), 128u);
  EXPECT_EQ(byteAt(ply.payload, v1 + 25), 255u);
  EXPECT_EQ(byteAt(ply.payload, v1 + 26), 0u);
  EXPECT_EQ(byteAt(ply.payload, v1 + 27), 64u);
  // Its back copy (vertex 9): same position, negated normal.
  const std::size_t b1 = 9 * 28;
  EXPECT_FLOAT_EQ(floatAt(ply.payload, b1 + 4), 0.02f);
  EXPECT_FLOAT_EQ(floatAt(ply.payload, b1 + 12), static_cast<float>(-n.x()));
  EXPECT_FLOAT_EQ(floatAt(ply.payload, b1 + 20), static_cast<float>(-n.z()));
  // Mesh 1 vertex 3 (file vertex 16 + 3): x = 0.5, clamped colour (255, 0, 255, 0).
  const std::size_t m1 = 19 * 28;
  EXPECT_FLOAT_EQ(floatAt(ply.payload, m1), 0.5f);
  EXPECT_FLOAT_EQ(floatAt(ply.payload, m1 + 8), -0.1f);
  EXPECT_EQ(byteAt(ply.payload, m1 + 24), 255u);
  EXPECT_EQ(byteAt(ply.payload, m1 + 26), 255u);
  EXPECT_EQ(byteAt(ply.payload, m1 + 27), 0u);

  // Faces: mesh 0 front (0 1 2), (1 3 2), ...; then its back copies flipped: (8 10 9), ...
  const std::size_t faces = 32 * 28;
  auto face = [&](int f) {
    const std::size_t at = faces + static_cast<std::size_t>(f) * 13;
    EXPECT_EQ(byteAt(ply.payload, at), 3u);
    return std::vector<int>{intAt(ply.payload, at + 1), intAt(ply.payload, at + 5),
                            intAt(ply.payload, at + 9)};
  };
  EXPECT_EQ(face(0), (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(face(1), (std::vector<int>{1, 3, 2}));
  EXPECT_EQ(face(6), (std::vector<int>{8, 10, 9}));
  EXPECT_EQ(face(12), (std::vector<int>{16, 17, 18}));  // mesh 1 starts after 16 vertices
  EXPECT_EQ(face(23), (std::vector<int>{16 + 8 + 5, 16 + 8 + 6, 16 + 8 + 7}));
  for (int f = 0; f < 24; ++f) {
    for (int index : face(f)) {
      EXPECT_GE(index, 0);
      EXPECT_LT(index, 32);
    }
  }
}

TEST(PlyWriterTest, NoColoursMeansOpaqueWhite) {
  const std::string path = test::tempPath("ply_writer_white.ply");
  PlyWriter::write(path, {smallMesh(0.0)}, {});
  const PlyFile ply = readPly(path);
  ASSERT_EQ(ply.payload.size(), 16u * 28u + 12u * 13u);
  for (std::size_t v = 0; v < 16; ++v) {
    for (std::size_t c = 24; c < 28; ++c) {
      EXPECT_EQ(byteAt(ply.payload, v * 28 + c), 255u);
    }
  }
}

TEST(PlyWriterTest, BadPathThrowsNamingIt) {
  const std::string path = "/nonexistent_hair_sim_dir/sub/strips.ply";
  try {
    PlyWriter::write(path, {smallMesh(0.0)}, {});
    ADD_FAILURE() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("No such file or directory"), std::string::npos) << e.what();
  }
}

TEST(PlyWriterTest, InconsistentInputsThrow) {
  const std::string path = test::tempPath("ply_writer_bad.ply");
  // Each message says what does not fit (smallMesh has 8 vertices).
  test::expectInvalid([&] { PlyWriter::write(path, {smallMesh(0.0)}, {std::vector<Rgba>(7)}); },
                      "colours of mesh 0 must have 8 entries, got 7");
  test::expectInvalid(
      [&] {
        PlyWriter::write(path, {smallMesh(0.0)}, {std::vector<Rgba>(8), std::vector<Rgba>(8)});
      },
      "one entry per mesh (1), got 2");
  StripMesh broken = smallMesh(0.0);
  broken.normals.pop_back();
  test::expectInvalid([&] { PlyWriter::write(path, {broken}, {}); }, "with 8 positions and 7 normals");
}

}  // namespace
}  // namespace hair_sim
