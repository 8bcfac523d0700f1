#pragma once

#include <cstdint>
#include <map>
#include <vector>

#include "core/trace/importance_map.h"

namespace fenestra {

// What pilot paths saw in one cell: the sum over their reflections there of
// (eventual score / weight leaving the reflection), and how many reflections.
struct ImportanceCell {
  double score_sum = 0;
  double visits = 0;
};

// The importance of the cells pilot paths visited, stored for ImportanceMap lookups.
// A cell's importance is shrunk towards the mean over all reflections by kPriorVisits
// pseudo-visits, so that rarely visited cells do not swing the weight windows.
class ImportanceTable {
 public:
  static constexpr double kPriorVisits = 5;

  ImportanceTable() = default;
  // Builds the table from per-cell sums, cells of `cell_m` metres.
  static ImportanceTable Build(const std::map<uint64_t, ImportanceCell>& cells, float cell_m);

  // A view for the tracer; valid while this table lives and is not modified.
  ImportanceMap Map() const;
  size_t CellCount() const { return cell_count_; }
  // Mean importance over all pilot reflections (the importance of unvisited cells).
  double MeanImportance() const { return fallback_; }

 private:
  float inverse_cell_m_ = 1;
  size_t cell_count_ = 0;
  float fallback_ = 0;
  std::vector<uint64_t> keys_ = {kEmptyCellKey};
  std::vector<float> values_ = {0.0f};
};

}  // namespace fenestra
