#include "hair_sim/core/geometry/BSplineSurface.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace hair_sim {

namespace {

std::string vecToString(const Vec3& p) {
  return "(" + std::to_string(p.x()) + ", " + std::to_string(p.y()) + ", " + std::to_string(p.z()) + ")";
}

void validate(const Vec3* points, int columns, int rows) {
  const char* where = "BSplineSurface::BSplineSurface(...) : ";
  if (points == nullptr) {
    throw std::invalid_argument(std::string(where) + "control_points is null");
  }
  if (columns < 2) {
    throw std::invalid_argument(std::string(where) + "columns must be >= 2, got " + std::to_string(columns));
  }
  if (rows < 4) {
    throw std::invalid_argument(std::string(where) + "rows must be >= 4, got " + std::to_string(rows));
  }
  for (int i = 0; i < columns * rows; ++i) {
    if (!points[i].allFinite()) {
      throw std::invalid_argument(std::string(where) + "control point " + std::to_string(i) + " (column " +
                                  std::to_string(i % columns) + ", row " + std::to_string(i / columns) +
                                  ") is not finite: " + vecToString(points[i]));
    }
  }
}

}  // namespace

BSplineSurface::BSplineSurface(const Vec3* control_points, int columns, int rows)
    : points_(control_points), columns_(columns), rows_(rows), degree_across_(0) {
  validate(control_points, columns, rows);
  degree_across_ = degreeAcross(columns);
}

BSplineSurface::BSplineSurface(const std::vector<Vec3>& control_points, int columns, int rows)
    : points_(control_points.data()), columns_(columns), rows_(rows), degree_across_(0) {
  if (columns >= 2 && rows >= 4 &&
      control_points.size() != static_cast<std::size_t>(columns) * static_cast<std::size_t>(rows)) {
    throw std::invalid_argument("BSplineSurface::BSplineSurface(...) : control_points has " +
                                std::to_string(control_points.size()) +
                                " points, columns * rows = " + std::to_string(columns * rows));
  }
  validate(control_points.empty() ? nullptr : control_points.data(), columns, rows);
  degree_across_ = degreeAcross(columns);
}

const Vec3& BSplineSurface::controlPoint(int column, int row) const {
  if (column < 0 || column >= columns_ || row < 0 || row >= rows_) {
    throw std::out_of_range("BSplineSurface::controlPoint(...) : (column " + std::to_string(column) +
                            ", row " + std::to_string(row) + ") outside the " + std::to_string(columns_) +
                            " x " + std::to_string(rows_) + " grid");
  }
  return points_[row * columns_ + column];
}

Vec3 BSplineSurface::extendedControlPoint(int column, int row) const {
  if (column < -1 || column > columns_ || row < -1 || row > rows_) {
    throw std::out_of_range("BSplineSurface::extendedControlPoint(...) : (column " + std::to_string(column) +
                            ", row " + std::to_string(row) + ") outside the extended grid [-1, " +
                            std::to_string(columns_) + "] x [-1, " + std::to_string(rows_) + "]");
  }
  // Reflection across u inside one real row.
  auto in_row = [this, column](int r) -> Vec3 {
    const Vec3* row_points = points_ + r * columns_;
    if (column == -1) {
      return 2.0 * row_points[0] - row_points[1];
    }
    if (column == columns_) {
      return 2.0 * row_points[columns_ - 1] - row_points[columns_ - 2];
    }
    return row_points[column];
  };
  if (row == -1) {
    return 2.0 * in_row(0) - in_row(1);
  }
  if (row == rows_) {
    return 2.0 * in_row(rows_ - 1) - in_row(rows_ - 2);
  }
  return in_row(row);
}

Vec3 BSplineSurface::deBoor(Vec3* d, int degree, double t, Vec3* derivative) {
  // Uniform knots k_m = m, span [k_s, k_s+1], local t = x - k_s, d[i] = c[s - p + i]:
  // alpha(r, i) = (x - k_{s-p+i}) / (k_{s+1+i-r} - k_{s-p+i}) = (t + p - i) / (p + 1 - r).
  for (int r = 1; r <= degree; ++r) {
    if (r == degree && derivative != nullptr) {
      // C'(x) = p (d[p] - d[p-1]) / (k_{s+1} - k_s) with the level p-1 points.
      *derivative = static_cast<double>(degree) * (d[degree] - d[degree - 1]);
    }
    const double denominator = static_cast<double>(degree + 1 - r);
    for (int i = degree; i >= r; --i) {
      const double alpha = (t + static_cast<double>(degree - i)) / denominator;
      d[i] = (1.0 - alpha) * d[i - 1] + alpha * d[i];
    }
  }
  return d[degree];
}

void BSplineSurface::locate(double u, double v, int& first_column, double& s, int& first_row,
                            double& t) const {
  if (!(u >= 0.0 && u <= 1.0) || !(v >= 0.0 && v <= 1.0)) {
    throw std::invalid_argument("BSplineSurface::evaluate(...) : (u, v) must lie in [0, 1] x [0, 1], got (" +
                                std::to_string(u) + ", " + std::to_string(v) + ")");
  }
  const double y = v * static_cast<double>(rows_ - 1);
  const int span = std::min(static_cast<int>(y), rows_ - 2);
  first_row = span - 1;
  t = y - static_cast<double>(span);

  const double x = u * static_cast<double>(columns_ - 1);
  if (degree_across_ == 2) {
    const int piece = std::min(static_cast<int>(std::floor(x + 0.5)), columns_ - 1);
    first_column = piece - 1;
    s = x - static_cast<double>(piece) + 0.5;
  } else {
    const int piece = std::min(static_cast<int>(x), columns_ - 2);
    first_column = degree_across_ == 3 ? piece - 1 : piece;
    s = x - static_cast<double>(piece);
  }
}

Vec3 BSplineSurface::evaluate(double u, double v) const {
  Vec3 position;
  Vec3 d_du;
  Vec3 d_dv;
  evaluate(u, v, position, d_du, d_dv);
  return position;
}

void BSplineSurface::evaluate(double u, double v, Vec3& position, Vec3& d_du, Vec3& d_dv) const {
  int first_column = 0;
  int first_row = 0;
  double s = 0.0;
  double t = 0.0;
  locate(u, v, first_column, s, first_row, t);

  // Across u on the four extended rows of the v span, then along v.
  Vec3 row_points[kDegreeAlong + 1];
  Vec3 row_derivatives[kDegreeAlong + 1];
  Vec3 work[4];
  for (int a = 0; a <= kDegreeAlong; ++a) {
    for (int b = 0; b <= degree_across_; ++b) {
      work[b] = extendedControlPoint(first_column + b, first_row + a);
    }
    row_points[a] = deBoor(work, degree_across_, s, &row_derivatives[a]);
  }
  Vec3 d_dt;
  position = deBoor(row_points, kDegreeAlong, t, &d_dt);
  const Vec3 d_ds = deBoor(row_derivatives, kDegreeAlong, t, nullptr);
  d_du = d_ds * static_cast<double>(columns_ - 1);
  d_dv = d_dt * static_cast<double>(rows_ - 1);
}

}  // namespace hair_sim
