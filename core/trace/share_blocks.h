#pragma once

#include <vector>

namespace fenestra {

// Splits `total` blocks among rows in proportion to their `work`, at least one block each
// (more than `total` in all when the rows outnumber it; equal shares when no row has work).
// Returns where each row's blocks start and, last, how many there are: rows + 1 entries.
std::vector<unsigned int> ShareBlocks(const std::vector<double>& work, unsigned int total);

}  // namespace fenestra
