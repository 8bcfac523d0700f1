#include "core/trace/share_blocks.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace fenestra {

std::vector<unsigned int> ShareBlocks(const std::vector<double>& work, unsigned int total) {
  const size_t rows = work.size();
  total = std::max<unsigned int>(total, static_cast<unsigned int>(rows));
  double sum = 0;
  for (const double w : work) sum += std::max(0.0, w);
  // One block each, the rest by share; what rounding down leaves goes to the largest remainders
  const double extra = total - static_cast<double>(rows);
  std::vector<unsigned int> blocks(rows, 1);
  std::vector<double> remainder(rows, 0.0);
  unsigned int given = static_cast<unsigned int>(rows);
  for (size_t y = 0; y < rows; ++y) {
    const double share = sum > 0 ? extra * std::max(0.0, work[y]) / sum : extra / rows;
    const double whole = std::floor(share);
    blocks[y] += static_cast<unsigned int>(whole);
    given += static_cast<unsigned int>(whole);
    remainder[y] = share - whole;
  }
  std::vector<size_t> order(rows);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return remainder[a] > remainder[b]; });
  for (size_t k = 0; given < total && k < rows; ++k, ++given) ++blocks[order[k]];
  std::vector<unsigned int> first(rows + 1, 0);
  for (size_t y = 0; y < rows; ++y) first[y + 1] = first[y] + blocks[y];
  return first;
}

}  // namespace fenestra
