#include "core/trace/importance.h"

namespace fenestra {

ImportanceTable ImportanceTable::Build(const std::map<uint64_t, ImportanceCell>& cells,
                                       float cell_m) {
  ImportanceTable table;
  table.inverse_cell_m_ = 1.0f / cell_m;
  table.cell_count_ = cells.size();
  double score_sum = 0, visits = 0;
  for (const auto& [key, cell] : cells) {
    score_sum += cell.score_sum;
    visits += cell.visits;
  }
  const double prior = visits > 0 ? score_sum / visits : 0.0;
  table.fallback_ = static_cast<float>(prior);

  // Open addressing, at most half full, filled in key order (deterministic layout)
  size_t capacity = 16;
  while (capacity < 2 * cells.size()) capacity *= 2;
  table.keys_.assign(capacity, kEmptyCellKey);
  table.values_.assign(capacity, 0.0f);
  const uint32_t mask = static_cast<uint32_t>(capacity - 1);
  for (const auto& [key, cell] : cells) {
    uint32_t slot = static_cast<uint32_t>(HashCellKey(key)) & mask;
    while (table.keys_[slot] != kEmptyCellKey) slot = (slot + 1) & mask;
    table.keys_[slot] = key;
    table.values_[slot] =
        static_cast<float>((cell.score_sum + kPriorVisits * prior) / (cell.visits + kPriorVisits));
  }
  return table;
}

ImportanceMap ImportanceTable::Map() const {
  return {inverse_cell_m_, static_cast<uint32_t>(keys_.size() - 1), keys_.data(), values_.data(),
          fallback_};
}

}  // namespace fenestra
