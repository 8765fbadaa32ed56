#include "hemo/gpu/primitives.hpp"

#include "hemo/gpu/pipeline_cache.hpp"
#include "interface/scan.h"
#include "interface/sort.h"

namespace hemo::gpu {

namespace {
constexpr std::uint32_t kWorkgroup = 256;

struct ScanPush {
  std::uint32_t n;
  std::uint32_t lengthIndex = HEMO_SCAN_NO_LENGTH;
  std::uint32_t lengthPlus = 0;
  std::uint32_t level = 0;
};
static_assert(sizeof(ScanPush) == 16);

struct ReducePush {
  std::uint32_t n;
};
static_assert(sizeof(ReducePush) == 4);

struct SortPush {
  std::uint32_t n;
  std::uint32_t shift;
  std::uint32_t chunkSize;
  std::uint32_t chunkCount;
  std::uint32_t digitBits;
};
static_assert(sizeof(SortPush) == 20);

std::uint64_t ceilDiv(std::uint64_t a, std::uint64_t b) { return (a + b - 1) / b; }

void checkCount(std::uint64_t n, std::uint64_t capacity, const char* what) {
  if (n > capacity) {
    throw std::invalid_argument(std::string(what) + ": n = " + std::to_string(n) +
                                " exceeds the capacity " + std::to_string(capacity));
  }
  if (n > 0xffffffffull) throw std::invalid_argument(std::string(what) + ": n must fit in 32 bits");
}
}  // namespace

std::uint32_t bitsFor(std::uint64_t maxValue) {
  std::uint32_t bits = 0;
  while (bits < 64 && (maxValue >> bits) != 0) ++bits;
  return bits;
}

// ---------------------------------------------------------------------------------------------
PrefixScan::PrefixScan(Context& context, const Buffer& data, std::uint64_t capacity, VkDeviceSize byteOffset,
                       const Buffer* lengths)
    : capacity_(capacity), noLengths_(context, 16, MemoryUse::Device, "scan: no GPU length") {
  const Buffer* lengthBuffer = lengths ? lengths : &noLengths_;
  checkCount(capacity, 0xffffffffull, "PrefixScan");
  if (byteOffset + capacity * 4 > data.allocatedSize()) {
    throw std::invalid_argument("PrefixScan: buffer '" + data.name() + "' is smaller than " +
                                std::to_string(capacity) + " uint32 elements");
  }
  blockScan_ = &context.pipelines().get({"scan/scan_block", HEMO_SCAN_BINDING_COUNT, sizeof(ScanPush), kWorkgroup, {}});
  addOffsets_ = &context.pipelines().get({"scan/scan_add", HEMO_SCAN_BINDING_COUNT, sizeof(ScanPush), kWorkgroup, {}});
  const std::uint64_t block = blockSize();
  // Level k scans `len` elements and writes ceil(len / block) totals; stop when one block.
  std::uint64_t len = capacity;
  const Buffer* level = &data;
  VkDeviceSize offset = byteOffset;
  while (true) {
    const std::uint64_t blocks = std::max<std::uint64_t>(ceilDiv(len, block), 1);
    sums_.emplace_back(context, blocks * 4, MemoryUse::Device, "scan block sums L" + std::to_string(sums_.size()));
    sets_.push_back(blockScan_->makeSet({{HEMO_SCAN_BINDING_DATA, level, offset, std::max<std::uint64_t>(len, 1) * 4},
                                         {HEMO_SCAN_BINDING_SUMS, &sums_.back()},
                                         {HEMO_SCAN_BINDING_LENGTH, lengthBuffer}}));
    if (blocks <= 1) break;
    level = &sums_.back();
    offset = 0;
    len = blocks;
  }
}

std::uint64_t PrefixScan::blockSize() const { return std::uint64_t(kWorkgroup) * HEMO_SCAN_ITEMS; }

void PrefixScan::record(CommandRecorder& rec, std::uint64_t n) const {
  checkCount(n, capacity_, "PrefixScan");
  if (n == 0) return;
  recordLevels(rec, n, HEMO_SCAN_NO_LENGTH, 0);
}

void PrefixScan::recordGpuLength(CommandRecorder& rec, std::uint32_t lengthIndex, std::uint32_t lengthPlus) const {
  if (capacity_ == 0) return;
  recordLevels(rec, capacity_, lengthIndex, lengthPlus);
}

void PrefixScan::recordLevels(CommandRecorder& rec, std::uint64_t n, std::uint32_t lengthIndex,
                              std::uint32_t lengthPlus) const {
  const std::uint64_t block = blockSize();
  std::vector<std::uint64_t> lengths;
  std::uint64_t len = n;
  for (std::size_t k = 0; k < sets_.size(); ++k) {
    lengths.push_back(len);
    rec.dispatch(*blockScan_, sets_[k],
                 ScanPush{static_cast<std::uint32_t>(len), lengthIndex, lengthPlus, static_cast<std::uint32_t>(k)},
                 blockScan_->groupsFor(len, HEMO_SCAN_ITEMS));
    rec.computeToCompute();
    if (len <= block) break;
    len = ceilDiv(len, block);
  }
  // Down-sweep: level k gets the scanned totals of level k + 1 added to its blocks.
  for (std::size_t k = lengths.size() - 1; k-- > 0;) {
    rec.dispatch(*addOffsets_, sets_[k],
                 ScanPush{static_cast<std::uint32_t>(lengths[k]), lengthIndex, lengthPlus, static_cast<std::uint32_t>(k)},
                 addOffsets_->groupsFor(lengths[k], HEMO_SCAN_ITEMS));
    rec.computeToCompute();
  }
}

// ---------------------------------------------------------------------------------------------
MinMaxReduce::MinMaxReduce(Context& context, const Buffer& values, std::uint64_t capacity)
    : capacity_(capacity),
      partials_(context, ceilDiv(std::max<std::uint64_t>(capacity, 1), std::uint64_t(kWorkgroup) * HEMO_REDUCE_ITEMS) * 8,
                MemoryUse::Device, "min/max partials"),
      counter_(context, 4, MemoryUse::Device, "min/max finished workgroups"),
      result_(context, 8, MemoryUse::Device, "min/max result") {
  checkCount(capacity, 0xffffffffull, "MinMaxReduce");
  reduce_ = &context.pipelines().get(
      {"scan/reduce_minmax", HEMO_REDUCE_BINDING_COUNT, sizeof(ReducePush), kWorkgroup, {}, 0u, 1u << HEMO_REDUCE_BINDING_VALUES});
  set_ = reduce_->makeSet({texelBinding(HEMO_REDUCE_BINDING_VALUES, &values, texel::kFloat),
                           {HEMO_REDUCE_BINDING_PARTIALS, &partials_},
                           {HEMO_REDUCE_BINDING_COUNTER, &counter_},
                           {HEMO_REDUCE_BINDING_RESULT, &result_}});
  counter_.upload(std::vector<std::uint32_t>{0u});
}

void MinMaxReduce::record(CommandRecorder& rec, std::uint64_t n) const {
  checkCount(n, capacity_, "MinMaxReduce");
  if (n == 0) {
    rec.fill(result_, 0x7f800000u, 0, 4);  // +inf
    rec.fill(result_, 0xff800000u, 4, 4);  // -inf
    rec.transferToCompute();
    return;
  }
  rec.dispatch(*reduce_, set_, ReducePush{static_cast<std::uint32_t>(n)}, reduce_->groupsFor(n, HEMO_REDUCE_ITEMS));
  rec.computeToCompute();
}

// ---------------------------------------------------------------------------------------------
namespace {
constexpr std::uint32_t kSortChunk = 512;  // pairs per invocation (tuned on lavapipe, see docs/benchmarks.md)
}

RadixSort::RadixSort(Context& context, const Buffer& pairs, std::uint64_t capacity)
    : pairs_(&pairs),
      capacity_(capacity),
      chunkSize_(kSortChunk),
      scratch_(context, std::max<std::uint64_t>(capacity, 1) * 8, MemoryUse::Device, "radix sort scratch"),
      counts_(context, std::max<std::uint64_t>(HEMO_RADIX_BUCKETS * ceilDiv(capacity, kSortChunk), 1) * 4,
              MemoryUse::Device, "radix sort bucket counts"),
      scan_(context, counts_, HEMO_RADIX_BUCKETS * ceilDiv(capacity, kSortChunk)) {
  checkCount(capacity, 0xffffffffull, "RadixSort");
  if (capacity * 8 > pairs.allocatedSize()) {
    throw std::invalid_argument("RadixSort: buffer '" + pairs.name() + "' is smaller than " +
                                std::to_string(capacity) + " pairs");
  }
  // The pairs read (and the scatter's offsets) are texel slots: llvmpipe reads a storage
  // buffer lane by lane.
  histogram_ = &context.pipelines().get({"sort/radix_histogram", HEMO_SORT_BINDING_COUNT, sizeof(SortPush), kWorkgroup,
                                         {}, 0u, 1u << HEMO_SORT_BINDING_PAIRS_IN});
  scatter_ = &context.pipelines().get({"sort/radix_scatter", HEMO_SORT_BINDING_COUNT, sizeof(SortPush), kWorkgroup, {}, 0u,
                                       1u << HEMO_SORT_BINDING_PAIRS_IN | 1u << HEMO_SORT_BINDING_COUNTS});
  // The histogram pass only reads pairs and writes counts; PAIRS_OUT is bound but unused.
  histFromPairs_ = histogram_->makeSet({texelBinding(HEMO_SORT_BINDING_PAIRS_IN, &pairs, texel::kUvec2),
                                        {HEMO_SORT_BINDING_COUNTS, &counts_},
                                        {HEMO_SORT_BINDING_PAIRS_OUT, &scratch_}});
  histFromScratch_ = histogram_->makeSet({texelBinding(HEMO_SORT_BINDING_PAIRS_IN, &scratch_, texel::kUvec2),
                                          {HEMO_SORT_BINDING_COUNTS, &counts_},
                                          {HEMO_SORT_BINDING_PAIRS_OUT, &pairs}});
  scatterToScratch_ = scatter_->makeSet({texelBinding(HEMO_SORT_BINDING_PAIRS_IN, &pairs, texel::kUvec2),
                                         texelBinding(HEMO_SORT_BINDING_COUNTS, &counts_, texel::kUint),
                                         {HEMO_SORT_BINDING_PAIRS_OUT, &scratch_}});
  scatterToPairs_ = scatter_->makeSet({texelBinding(HEMO_SORT_BINDING_PAIRS_IN, &scratch_, texel::kUvec2),
                                       texelBinding(HEMO_SORT_BINDING_COUNTS, &counts_, texel::kUint),
                                       {HEMO_SORT_BINDING_PAIRS_OUT, &pairs}});
}

std::uint32_t RadixSort::passesFor(std::uint32_t keyBits) {
  return (std::min<std::uint32_t>(keyBits, 32) + HEMO_RADIX_BITS - 1) / HEMO_RADIX_BITS;
}

void RadixSort::record(CommandRecorder& rec, std::uint64_t n, std::uint32_t keyBits, bool keysInScratch) const {
  checkCount(n, capacity_, "RadixSort");
  const std::uint32_t passes = n <= 1 ? 0u : passesFor(keyBits);  // 0: already sorted
  // Pass p reads the pairs buffer when p is even, unless the keys start in scratch; the
  // result is wherever the last pass wrote.
  const bool endsInScratch = (passes % 2 == 1) != keysInScratch;
  if (passes > 0) {
    const std::uint32_t digitBits = (std::min<std::uint32_t>(keyBits, 32) + passes - 1) / passes;
    const std::uint64_t chunks = chunkCount(n);
    const std::uint64_t buckets = std::uint64_t(1) << digitBits;
    for (std::uint32_t pass = 0; pass < passes; ++pass) {
      const bool fromPairs = (pass % 2 == 0) != keysInScratch;
      const SortPush push{static_cast<std::uint32_t>(n), pass * digitBits, chunkSize_,
                          static_cast<std::uint32_t>(chunks), digitBits};
      rec.dispatch(*histogram_, fromPairs ? histFromPairs_ : histFromScratch_, push, histogram_->groupsFor(chunks));
      rec.computeToCompute();
      scan_.record(rec, buckets * chunks);
      rec.dispatch(*scatter_, fromPairs ? scatterToScratch_ : scatterToPairs_, push, scatter_->groupsFor(chunks));
      rec.computeToCompute();
    }
  }
  if (endsInScratch && n > 0) {
    rec.computeToTransfer();
    rec.copy(scratch_, *pairs_, n * 8);
    rec.transferToCompute();
  }
}

}  // namespace hemo::gpu
