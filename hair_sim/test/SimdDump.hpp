#pragma once
/// Shared by the bit-identity dump programs (TessellatorSimdDump, HairLookSimdDump, PinchMemoryDump and
/// fuzz_messages' state hash): a byte hash and deterministic curved strips.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "hair_sim/core/TypeDefs.hpp"

namespace hair_sim {
namespace simd_dump {

/// FNV-1a's offset basis: where a hash starts.
constexpr std::uint64_t kHashBasis = 14695981039346656037ULL;

/// FNV-1a over raw bytes, continuing `hash`.
inline void hashBytes(std::uint64_t& hash, const void* data, std::size_t size) {
  const unsigned char* bytes = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < size; ++i) {
    hash = (hash ^ bytes[i]) * 1099511628211ULL;
  }
}

/// FNV-1a of raw bytes, from the offset basis.
inline std::uint64_t hashOf(const void* data, std::size_t size) {
  std::uint64_t hash = kHashBasis;
  hashBytes(hash, data, size);
  return hash;
}

/// A curved strip (trigonometric bends), deterministic: `seed` varies it; the pitch starts at pitch0 and
/// swings by pitch_swing, the yaw by yaw_swing (rad), 8 cm segments.
inline std::vector<Vec3> curvedGrid(int columns, int rows, int seed, double pitch0, double pitch_swing,
                                    double yaw_swing) {
  std::vector<Vec3> points(static_cast<std::size_t>(columns * rows));
  for (int c = 0; c < columns; ++c) {
    Vec3 p(0.001 * std::sin(seed + c), 0.015 * c, 0.001 * std::cos(3 * seed + c));
    double pitch = pitch0;
    for (int r = 0; r < rows; ++r) {
      points[static_cast<std::size_t>(r * columns + c)] = p;
      pitch += pitch_swing * std::sin(1.7 * r + seed) + 0.05 * c;
      const double yaw = yaw_swing * std::cos(2.3 * r + seed + c);
      p += 0.08 * Vec3(std::cos(pitch) * std::cos(yaw), std::sin(yaw), -std::sin(pitch)).normalized();
    }
  }
  return points;
}

}  // namespace simd_dump
}  // namespace hair_sim
