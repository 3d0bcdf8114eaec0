#pragma once
/// One hair strip (paper section 3): a uniform B-spline patch over a control grid of `columns`
/// (across the width, >= 2) x `rows` (along the hair, >= 4) points, in the head frame, row-major
/// (index = row * columns + column). Row 0 is the root row, fixed to the scalp.
#include <string>
#include <vector>

#include "hair_sim/core/TypeDefs.hpp"

namespace hair_sim {

struct Strip {
  static constexpr int kMinColumns = 2;
  static constexpr int kMinRows = 4;
  /// The largest grid the hairstyle loader takes (and hair_sim_generate makes).
  static constexpr int kMaxColumns = 64;
  static constexpr int kMaxRows = 256;
  /// The ranges Hairstyle::validate (and so the loader, the generator and the Simulator) takes (m).
  static constexpr double kMinHairLength = 1e-3;
  static constexpr double kMaxHairLength = 10.0;
  static constexpr double kMinWidth = 1e-4;
  static constexpr double kMaxWidth = 1.0;
  static constexpr double kMaxThicknessMargin = 0.1;

  std::string name;
  int columns = 2;
  int rows = 5;
  /// Control points in the head frame (m), rows * columns of them, row-major.
  std::vector<Vec3> points;
  /// Length of the hair along the strip (m): where tessellation stops.
  double hair_length = 0.25;
  /// Width across the strip at the root (m); informative, the grid defines the shape.
  double width = 0.03;
  /// Half thickness kept between the strip and every body (m): bodies are inflated by it.
  double thickness_margin = 0.004;
  /// Base colour (linear RGB) and opacity.
  Rgba color{0.25f, 0.16f, 0.09f, 1.0f};

  int index(int row, int column) const { return row * columns + column; }
  const Vec3& point(int row, int column) const {
    return points[static_cast<std::size_t>(index(row, column))];
  }
  Vec3& point(int row, int column) { return points[static_cast<std::size_t>(index(row, column))]; }
  int pointCount() const { return rows * columns; }
  /// Sum of the segment lengths of one column (m).
  double columnLength(int column) const;
};

}  // namespace hair_sim
