#pragma once
// Data-parallel building blocks on the GPU: exclusive prefix scan of uint32, min/max
// reduction of float32 and a stable radix sort of (uint32 key, uint32 value) pairs.
// Each object is bound to its buffers at construction (descriptor sets are made once) and
// records its dispatches into a CommandRecorder for any n up to its capacity. Results are
// deterministic: no float atomics, fixed association order.
#include "hemo/gpu/commands.hpp"

#include <cstdint>
#include <deque>
#include <vector>

namespace hemo::gpu {

// In-place exclusive prefix sum of data[0, n) (uint32, wrapping on overflow like
// std::exclusive_scan on uint32_t). Multi-level: one block scan per level, then adds.
class PrefixScan {
 public:
  // `lengths` (optional): a buffer of uint32 lengths the GPU computes, for recordGpuLength.
  PrefixScan(Context& context, const Buffer& data, std::uint64_t capacity, VkDeviceSize byteOffset = 0,
             const Buffer* lengths = nullptr);
  void record(CommandRecorder& rec, std::uint64_t n) const;
  // Scans lengths[lengthIndex] + lengthPlus elements (clamped to the capacity), a length only
  // the GPU knows: the dispatches are sized for the capacity and the surplus invocations do
  // nothing. Needs the `lengths` buffer given at construction, written before.
  void recordGpuLength(CommandRecorder& rec, std::uint32_t lengthIndex, std::uint32_t lengthPlus = 0) const;
  std::uint64_t capacity() const { return capacity_; }
  // Elements one workgroup scans.
  std::uint64_t blockSize() const;

 private:
  const ComputePipeline* blockScan_;
  const ComputePipeline* addOffsets_;
  void recordLevels(CommandRecorder& rec, std::uint64_t n, std::uint32_t lengthIndex, std::uint32_t lengthPlus) const;

  std::uint64_t capacity_;
  Buffer noLengths_;                  // bound when the scan has no GPU length
  std::deque<Buffer> sums_;           // block totals of each level
  std::vector<DescriptorSet> sets_;   // level k: data_k (user data or sums_{k-1}) with sums_k
};

// (min, max) of values[0, n) as a vec2 in result() (+inf, -inf for n = 0; NaN, NaN if any
// value is NaN), in one dispatch (scan/reduce_minmax.comp). The values are read as R32_SFLOAT
// texels, so `capacity` must stay within the device's maxTexelBufferElements. Recordings of one reducer must
// not run concurrently (they share the partials and the finished-workgroup counter); the
// barrier after each recording sees to that within a command buffer.
class MinMaxReduce {
 public:
  MinMaxReduce(Context& context, const Buffer& values, std::uint64_t capacity);
  void record(CommandRecorder& rec, std::uint64_t n) const;
  const Buffer& result() const { return result_; }

 private:
  const ComputePipeline* reduce_;
  std::uint64_t capacity_;
  Buffer partials_;  // vec2 per workgroup
  Buffer counter_;   // workgroups finished (0 between recordings)
  Buffer result_;
  DescriptorSet set_;
};

// Stable sort of pairs[0, n) (uvec2: x = key, y = value) by key, in place, using keyBits low
// bits of the key (keys must be < 2^keyBits). LSD radix sort with HEMO_RADIX_BITS per pass.
class RadixSort {
 public:
  RadixSort(Context& context, const Buffer& pairs, std::uint64_t capacity);
  // Sorts the first n pairs by key into the pairs buffer. With keysInScratch, the unsorted
  // pairs are in scratch() instead: a sort of an odd number of passes (passesFor) then ends
  // in the pairs buffer without the final copy, a transfer, which runs even when a dispatch
  // gate skips the sort's dispatches.
  void record(CommandRecorder& rec, std::uint64_t n, std::uint32_t keyBits = 32, bool keysInScratch = false) const;
  static std::uint32_t passesFor(std::uint32_t keyBits);
  const Buffer& scratch() const { return scratch_; }
  Buffer& scratch() { return scratch_; }

 private:
  std::uint64_t chunkCount(std::uint64_t n) const { return (n + chunkSize_ - 1) / chunkSize_; }

  const ComputePipeline* histogram_;
  const ComputePipeline* scatter_;
  const Buffer* pairs_;
  std::uint64_t capacity_;
  std::uint32_t chunkSize_;
  Buffer scratch_;
  Buffer counts_;
  PrefixScan scan_;
  DescriptorSet histFromPairs_, histFromScratch_, scatterToScratch_, scatterToPairs_;
};

// Bits needed to represent every value in [0, maxValue].
std::uint32_t bitsFor(std::uint64_t maxValue);

}  // namespace hemo::gpu
