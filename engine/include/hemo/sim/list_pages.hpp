#pragma once
// The pages of a neighbour list split where one buffer would pass a binding limit
// (interface/sph.h, "pages"): page p holds the slots [p * pageSlots, (p + 1) * pageSlots).
#include <algorithm>
#include <cstdint>

namespace hemo::sim {

// Calls fn(page, first, end) for each of the `pages` pages that holds some of the slots
// [begin, end), with [first, end) its share of them.
template <class Fn>
void forEachListPage(std::uint32_t pageSlots, std::uint32_t pages, std::uint32_t begin, std::uint32_t end, Fn fn) {
  for (std::uint32_t p = 0; p < pages; ++p) {
    const std::uint64_t lo = std::max<std::uint64_t>(begin, std::uint64_t(p) * pageSlots);
    const std::uint64_t hi = std::min<std::uint64_t>(end, std::uint64_t(p + 1) * pageSlots);
    if (lo < hi) fn(p, static_cast<std::uint32_t>(lo), static_cast<std::uint32_t>(hi));
  }
}

}  // namespace hemo::sim
