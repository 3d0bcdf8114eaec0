#include "hair_sim/core/model/Strip.hpp"

namespace hair_sim {

double Strip::columnLength(int column) const {
  double length = 0.0;
  for (int row = 1; row < rows; ++row) length += (point(row, column) - point(row - 1, column)).norm();
  return length;
}

}  // namespace hair_sim
