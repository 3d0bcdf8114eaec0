#pragma once
/// Uniform B-spline patch of one hair strip, evaluated by de Boor's algorithm (the reference evaluation).
#include <vector>

#include "hair_sim/core/TypeDefs.hpp"

namespace hair_sim {

/// Non-owning view of a strip's control grid as a uniform B-spline surface S(u, v), u, v in [0, 1].
///
/// Control grid: `columns` (across the width, >= 2) x `rows` (along the hair, >= 4) points, row-major,
/// index = row * columns + column; row 0 is the root row on the scalp.
///
/// Degrees: cubic along the hair (v); across the width (u) degree min(3, columns - 1), i.e. linear for
/// 2 columns, quadratic for 3, cubic for 4 or more.
///
/// End conditions (the same rule in both directions): the grid is extended by one reflected phantom point
/// at each end, P[-1] = 2 P[0] - P[1] and P[n] = 2 P[n-1] - P[n-2] (the corner phantoms are the reflection
/// of the reflection; reflections in u and v commute). The three end points P[-1], P[0], P[1] are then
/// collinear and equally spaced, so by the linear precision of uniform B-splines the curve passes
/// exactly through the end control point, tangent to the end segment, at the end point's Greville
/// abscissa. The parameter domain is the interval between the Greville abscissae of the first and the
/// last real control point, which has length n - 1 knot intervals in both directions:
///  - along v (cubic) and across u when linear or cubic: the knots sit at the control points, so the
///    domain is n - 1 whole polynomial spans; span j uses the extended points j-1..j+2 (cubic) or j..j+1
///    (linear).
///  - across u when quadratic (3 columns): Greville abscissae of a quadratic sit at mid-knots, so the
///    domain is shifted by half a knot interval: x = u (columns - 1) in [0, columns - 1], polynomial piece
///    i = round(x) (i = 0..columns-1) uses extended points i-1, i, i+1 with local parameter x - i + 1/2.
///    The first and last half pieces are straight (their three points are collinear): the u = 0 and
///    u = 1 edges are exactly the cubic curves of the first and the last control column.
/// Hence S(u, 0) is the curve of the root row, S(u, 1) that of the tip row, S(0, v) and S(1, v) the
/// curves of the outer columns, and S(0,0) = P(column 0, row 0) etc. exactly.
///
/// The view stores only the pointer: the control points must outlive it. Not thread-hostile: all
/// methods are const and allocation-free.
class BSplineSurface {
 public:
  /// Degree along the hair (v).
  static constexpr int kDegreeAlong = 3;

  /// Throws std::invalid_argument when control_points is null, columns < 2, rows < 4 or a coordinate is
  /// not finite.
  BSplineSurface(const Vec3* control_points, int columns, int rows);
  /// Same, and the vector size must equal columns * rows.
  BSplineSurface(const std::vector<Vec3>& control_points, int columns, int rows);

  int columns() const { return columns_; }
  int rows() const { return rows_; }
  /// Degree across the width: min(3, columns - 1).
  int degreeAcross() const { return degree_across_; }
  /// Degree across the width for a column count (columns >= 2 assumed).
  static int degreeAcross(int columns) { return columns >= 4 ? 3 : columns - 1; }

  /// Real control point (0 <= column < columns, 0 <= row < rows); throws std::out_of_range otherwise.
  const Vec3& controlPoint(int column, int row) const;
  /// Control point of the extended grid: column in [-1, columns], row in [-1, rows] (phantoms included);
  /// throws std::out_of_range otherwise.
  Vec3 extendedControlPoint(int column, int row) const;

  /// Surface point at (u, v), both in [0, 1]; throws std::invalid_argument when outside or NaN.
  Vec3 evaluate(double u, double v) const;
  /// Surface point and its partial derivatives with respect to u and v (units: m per unit parameter).
  void evaluate(double u, double v, Vec3& position, Vec3& d_du, Vec3& d_dv) const;

  /// de Boor's algorithm on one span of a uniform B-spline of degree `degree` (0 < degree <= 3) with unit
  /// knot spacing. points[0..degree] are the span's control points (overwritten), t in [0, 1] is the local
  /// parameter. Returns the curve point; when derivative is not null it receives dC/dt.
  static Vec3 deBoor(Vec3* points, int degree, double t, Vec3* derivative);

 private:
  void locate(double u, double v, int& first_column, double& s, int& first_row, double& t) const;

  const Vec3* points_;
  int columns_;
  int rows_;
  int degree_across_;
};

}  // namespace hair_sim
