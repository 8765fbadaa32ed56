// Stable radix sort of (key, value) pairs against std::stable_sort.
#include "gpu_test.hpp"
#include "hemo/gpu/primitives.hpp"

#include <glm/vec2.hpp>

#include <algorithm>
#include <limits>

namespace hemo::test {
namespace {

using Pairs = std::vector<glm::uvec2>;

class SortTest : public GpuTest {
 protected:
  // keysInScratch: the input goes to the sort's scratch buffer (RadixSort::record).
  Pairs gpuSort(const Pairs& input, std::uint32_t keyBits = 32, bool keysInScratch = false) {
    gpu::Buffer pairs(ctx(), std::max<std::size_t>(input.size(), 1) * 8, gpu::MemoryUse::Device, "pairs");
    gpu::RadixSort sort(ctx(), pairs, input.size());
    if (!input.empty()) {
      pairs.upload(Pairs(input.size(), glm::uvec2(0xdeadbeefu)));  // garbage where the keys are not
      (keysInScratch ? sort.scratch() : pairs).upload(input);
    }
    gpu::CommandRecorder rec(ctx());
    rec.begin();
    sort.record(rec, input.size(), keyBits, keysInScratch);
    rec.end();
    rec.submitAndWait();
    return pairs.readback<glm::uvec2>(input.size());
  }
  static Pairs cpuSort(Pairs input) {
    std::stable_sort(input.begin(), input.end(), [](const glm::uvec2& a, const glm::uvec2& b) { return a.x < b.x; });
    return input;
  }
  // Values are the input positions, so any instability shows.
  static Pairs withIndexValues(const std::vector<std::uint32_t>& keys) {
    Pairs p(keys.size());
    for (std::size_t i = 0; i < keys.size(); ++i) p[i] = {keys[i], static_cast<std::uint32_t>(i)};
    return p;
  }
};

TEST_F(SortTest, MatchesStableSortOnAwkwardSizes) {
  auto rng = rngFor();
  for (std::size_t n : {0u, 1u, 2u, 63u, 64u, 65u, 255u, 256u, 257u, 511u, 512u, 513u, 1000u, 65537u, 100001u, 1048583u}) {
    std::vector<std::uint32_t> keys(n);
    for (auto& k : keys) k = static_cast<std::uint32_t>(rng());
    const Pairs input = withIndexValues(keys);
    EXPECT_EQ(gpuSort(input), cpuSort(input)) << "n = " << n;
  }
}

TEST_F(SortTest, IsStableWithManyDuplicates) {
  auto rng = rngFor();
  std::vector<std::uint32_t> keys(200003);
  for (auto& k : keys) k = static_cast<std::uint32_t>(rng() % 37) * 0x01010101u;  // every byte matters
  const Pairs input = withIndexValues(keys);
  EXPECT_EQ(gpuSort(input), cpuSort(input));
}

TEST_F(SortTest, AllKeysEqual) {
  const Pairs input = withIndexValues(std::vector<std::uint32_t>(70000, 42u));
  EXPECT_EQ(gpuSort(input), input);
}

TEST_F(SortTest, KeysAtTheMaximum) {
  auto rng = rngFor();
  std::vector<std::uint32_t> keys(30011);
  for (auto& k : keys) k = (rng() % 3 == 0) ? std::numeric_limits<std::uint32_t>::max() : static_cast<std::uint32_t>(rng());
  const Pairs input = withIndexValues(keys);
  EXPECT_EQ(gpuSort(input), cpuSort(input));
}

TEST_F(SortTest, HonoursKeyBitsWithOddAndEvenPassCounts) {
  auto rng = rngFor();
  for (std::uint32_t bits : {0u, 1u, 8u, 9u, 17u, 24u}) {
    std::vector<std::uint32_t> keys(50021);
    for (auto& k : keys) k = bits == 0 ? 0u : static_cast<std::uint32_t>(rng()) & ((1u << bits) - 1u);
    const Pairs input = withIndexValues(keys);
    EXPECT_EQ(gpuSort(input, bits), cpuSort(input)) << bits << " key bits";
    // the same with the keys starting in the sort's scratch buffer (odd pass counts end in
    // the pairs without a copy; even ones and none copy at the end)
    EXPECT_EQ(gpuSort(input, bits, true), cpuSort(input)) << bits << " key bits, keys in scratch";
  }
  for (std::size_t n : {0u, 1u, 2u}) {
    const Pairs input = withIndexValues(std::vector<std::uint32_t>(n, 5u));
    EXPECT_EQ(gpuSort(input, 17, true), input) << n << " pairs in scratch";
  }
}

TEST_F(SortTest, AlreadySortedAndReversed) {
  std::vector<std::uint32_t> up(40000), down(40000);
  for (std::uint32_t i = 0; i < up.size(); ++i) {
    up[i] = i * 7;
    down[i] = 0xfffffff0u - i * 3;
  }
  EXPECT_EQ(gpuSort(withIndexValues(up)), withIndexValues(up));
  const Pairs d = withIndexValues(down);
  EXPECT_EQ(gpuSort(d), cpuSort(d));
}

}  // namespace
}  // namespace hemo::test
