#pragma once
/// Hairstyle YAML files. Format (head frame, metres):
///   format_version: 1
///   scalp: {center: [x, y, z], rpy: [r, p, y], radii: [a, b, c]}
///   strips:
///   (every coordinate within +-100 m, scalp radii in (0, 10] m)
///     - {name: s0, columns: 2, rows: 5, hair_length: 0.25, width: 0.03, thickness_margin: 0.004,
///        color: [r, g, b, a], points: [[x, y, z], ...]}   # rows * columns points, row-major, row 0 = roots
#include <string>

#include "hair_sim/core/model/Hairstyle.hpp"

namespace hair_sim {

/// Throws std::invalid_argument naming the file, the key and the bad value.
Hairstyle loadHairstyle(const std::string& path);
/// Writes the format above (numbers that read back bit-identically); throws std::runtime_error on I/O error.
void saveHairstyle(const Hairstyle& hairstyle, const std::string& path);

}  // namespace hair_sim
