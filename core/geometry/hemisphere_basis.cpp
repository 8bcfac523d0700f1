#include "core/geometry/hemisphere_basis.h"

#include <algorithm>
#include <numbers>
#include <vector>

namespace fenestra {

HemisphereBasis Beckers288() {
  static constexpr int kRings[] = {1, 8, 13, 19, 24, 29, 34, 37, 40, 41, 42};
  HemisphereBasis basis;
  basis.cell_count = 288;
  int total = 0;
  for (int count : kRings) {
    total += count;
    basis.cumulative[basis.ring_count++] = total;
  }
  return basis;
}

HemisphereBasis BeckersBasis(int cell_count) {
  if (cell_count == 288) return Beckers288();
  HemisphereBasis basis;
  if (cell_count < 1 || cell_count > 10000) return basis;
  const double n = cell_count;
  // From the horizon inwards: a ring as wide as a square cell, then round its cell count
  std::vector<int> cumulative = {cell_count};
  double theta = std::numbers::pi / 2;
  int k = cell_count;
  while (true) {
    const double next_theta = theta - 2 * std::sin(theta / 2) * std::sqrt(std::numbers::pi / k);
    if (next_theta <= 0) break;
    const int next_k = static_cast<int>(std::lround(n * (1 - std::cos(next_theta))));
    if (next_k < 1 || next_k >= k) break;
    cumulative.push_back(next_k);
    theta = std::acos(1 - next_k / n);
    k = next_k;
  }
  std::reverse(cumulative.begin(), cumulative.end());
  if (static_cast<int>(cumulative.size()) > HemisphereBasis::kMaxRings) return basis;
  basis.cell_count = cell_count;
  for (int c : cumulative) basis.cumulative[basis.ring_count++] = c;
  return basis;
}

Vec3d BasisCellCenter(const HemisphereBasis& basis, int cell) {
  return SampleBasisCell<double>(basis, cell, 0.5, 0.5);
}

}  // namespace fenestra
