// Exclusive prefix scan and min/max reduction against the standard library.
#include "gpu_test.hpp"
#include "hemo/gpu/gate.hpp"
#include "hemo/gpu/primitives.hpp"

#include <limits>
#include <numeric>

namespace hemo::test {
namespace {

class ScanTest : public GpuTest {
 protected:
  std::vector<std::uint32_t> gpuScan(const std::vector<std::uint32_t>& input) {
    gpu::Buffer data(ctx(), input.size() * 4, gpu::MemoryUse::Device, "scan data");
    data.upload(input);
    gpu::PrefixScan scan(ctx(), data, input.size());
    gpu::CommandRecorder rec(ctx());
    rec.begin();
    scan.record(rec, input.size());
    rec.end();
    rec.submitAndWait();
    return data.readback<std::uint32_t>(input.size());
  }
  static std::vector<std::uint32_t> cpuScan(const std::vector<std::uint32_t>& input) {
    std::vector<std::uint32_t> out(input.size());
    std::exclusive_scan(input.begin(), input.end(), out.begin(), 0u);
    return out;
  }
};

TEST_F(ScanTest, MatchesStdExclusiveScanOnAwkwardSizes) {
  auto rng = rngFor();
  std::uniform_int_distribution<std::uint32_t> small(0, 1000);
  for (std::size_t n : {0u, 1u, 2u, 7u, 63u, 64u, 65u, 255u, 256u, 257u, 2047u, 2048u, 2049u, 4095u, 4096u, 4097u, 8193u, 100003u,
                        524289u, 2048u * 2048u + 3u}) {
    std::vector<std::uint32_t> input(n);
    for (auto& v : input) v = small(rng);
    EXPECT_EQ(gpuScan(input), cpuScan(input)) << "n = " << n;
  }
}

TEST_F(ScanTest, WrapsLikeUint32AtTheMaximum) {
  std::vector<std::uint32_t> input(5000, std::numeric_limits<std::uint32_t>::max());
  input[17] = 3;
  EXPECT_EQ(gpuScan(input), cpuScan(input));
}

TEST_F(ScanTest, SixteenMillionElementsUseThreeLevels) {
  const std::size_t n = (1u << 24) + 12345;  // more than 4096^2: three levels of 4096-element blocks
  std::vector<std::uint32_t> input(n);
  auto rng = rngFor();
  for (auto& v : input) v = static_cast<std::uint32_t>(rng() & 3u);
  EXPECT_EQ(gpuScan(input), cpuScan(input));
}

TEST_F(ScanTest, RecordsForAnyCountUpToItsCapacity) {
  std::vector<std::uint32_t> input(10000);
  auto rng = rngFor();
  for (auto& v : input) v = static_cast<std::uint32_t>(rng() % 50);
  gpu::Buffer data(ctx(), input.size() * 4, gpu::MemoryUse::Device, "scan data");
  gpu::PrefixScan scan(ctx(), data, input.size());
  gpu::CommandRecorder rec(ctx());
  for (std::size_t n : {10000u, 3000u, 1u, 2049u}) {
    data.upload(input);
    rec.begin();
    scan.record(rec, n);
    rec.end();
    rec.submitAndWait();
    auto got = data.readback<std::uint32_t>(input.size());
    std::vector<std::uint32_t> expect(input);
    std::exclusive_scan(input.begin(), input.begin() + n, expect.begin(), 0u);
    EXPECT_EQ(got, expect) << "n = " << n << " (elements past n must stay untouched)";
  }
  EXPECT_THROW(scan.record(rec, 10001), std::invalid_argument);
}

// A length only the GPU knows: the scan is recorded for its capacity and scans
// lengths[index] + plus elements (clamped to the capacity), leaving the rest untouched.
TEST_F(ScanTest, ScansALengthTheGpuWrote) {
  const std::size_t capacity = 3 * 4096 * 4096 / 1000;  // 50,331: two levels
  std::vector<std::uint32_t> input(capacity);
  auto rng = rngFor();
  for (auto& v : input) v = static_cast<std::uint32_t>(rng() % 50);
  gpu::Buffer data(ctx(), capacity * 4, gpu::MemoryUse::Device, "scan data");
  gpu::Buffer lengths(ctx(), 16, gpu::MemoryUse::Device, "scan lengths");
  gpu::PrefixScan scan(ctx(), data, capacity, 0, &lengths);
  gpu::CommandRecorder rec(ctx());
  for (std::uint32_t length : {0u, 1u, 4095u, 4096u, 20000u, std::uint32_t(capacity) - 1, std::uint32_t(capacity) + 50}) {
    data.upload(input);
    lengths.upload(std::vector<std::uint32_t>{7u, length, 9u, 9u});
    rec.begin();
    scan.recordGpuLength(rec, 1, 1);
    rec.end();
    rec.submitAndWait();
    const std::size_t n = std::min<std::size_t>(length + 1, capacity);
    std::vector<std::uint32_t> expect(input);
    std::exclusive_scan(input.begin(), input.begin() + std::ptrdiff_t(n), expect.begin(), 0u);
    EXPECT_EQ(data.readback<std::uint32_t>(capacity), expect) << "length " << length << " + 1";
  }
}

// A dispatch gate runs its region (here a multi-dispatch prefix scan) only when the decision
// value exceeds the threshold or is NaN, counts its openings, and rejects a region whose
// dispatches change between recordings.
TEST_F(ScanTest, DispatchGateRunsItsRegionOnlyWhenOpen) {
  const std::size_t n = 70000;  // several scan levels, so several gated dispatches
  std::vector<std::uint32_t> input(n, 1u);
  gpu::Buffer data(ctx(), n * 4, gpu::MemoryUse::Device, "gated scan data");
  gpu::Buffer values(ctx(), 16, gpu::MemoryUse::Device, "gate values");
  gpu::PrefixScan scan(ctx(), data, n);
  gpu::DispatchGate gate(ctx(), values, 16, "test gate");
  gpu::CommandRecorder rec(ctx());
  auto run = [&](float value) {
    data.upload(input);
    values.upload(std::vector<float>{0.0f, value, 0.0f, 0.0f});
    rec.begin();
    gate.recordArm(rec, 1, 0.5f);
    rec.beginGate(gate);
    scan.record(rec, n);
    rec.endGate();
    rec.end();
    rec.submitAndWait();
    return data.readback<std::uint32_t>(n);
  };
  rec.begin();
  gate.recordReset(rec);
  rec.end();
  rec.submitAndWait();
  EXPECT_EQ(run(1.0f), cpuScan(input)) << "open";
  EXPECT_EQ(run(0.25f), input) << "closed: the scan must not run";
  EXPECT_EQ(run(0.5f), input) << "closed at the threshold itself";
  EXPECT_EQ(run(std::numeric_limits<float>::quiet_NaN()), cpuScan(input)) << "NaN opens";
  EXPECT_EQ(run(std::numeric_limits<float>::infinity()), cpuScan(input)) << "+inf opens";
  EXPECT_EQ(gate.readOpened(), 3u);

  rec.begin();
  rec.beginGate(gate);
  EXPECT_THROW(scan.record(rec, n / 2), std::logic_error);  // other workgroup counts
  rec.endGate();
  EXPECT_THROW(rec.endGate(), std::logic_error);
  rec.end();
}

// A gate of two variants holds two regions of different shapes (the solver's full and
// partial sorts): each runs with its own workgroup counts, and each still rejects a change.
TEST_F(ScanTest, DispatchGateVariantsHoldRegionsOfDifferentShapes) {
  const std::size_t n = 70000, m = 3000;  // three scan levels, then one
  std::vector<std::uint32_t> input(n, 1u);
  gpu::Buffer data(ctx(), n * 4, gpu::MemoryUse::Device, "gated scan data");
  gpu::Buffer values(ctx(), 16, gpu::MemoryUse::Device, "gate values");
  gpu::PrefixScan scan(ctx(), data, n);
  EXPECT_THROW(gpu::DispatchGate(ctx(), values, 4, "too many variants", 5), std::invalid_argument);
  gpu::DispatchGate gate(ctx(), values, 16, "test gate", 2);
  gpu::CommandRecorder rec(ctx());
  rec.begin();
  gate.recordReset(rec);
  rec.end();
  rec.submitAndWait();
  auto run = [&](std::uint32_t variant, std::size_t count, float value) {
    data.upload(input);
    values.upload(std::vector<float>{0.0f, value, 0.0f, 0.0f});
    rec.begin();
    gate.recordArm(rec, 1, 0.5f);
    rec.beginGate(gate, variant);
    scan.record(rec, count);
    rec.endGate();
    rec.end();
    rec.submitAndWait();
    return data.readback<std::uint32_t>(n);
  };
  auto expected = [&](std::size_t count) {
    std::vector<std::uint32_t> out = input;
    const std::vector<std::uint32_t> head = cpuScan(std::vector<std::uint32_t>(input.begin(), input.begin() + count));
    std::copy(head.begin(), head.end(), out.begin());
    return out;
  };
  for (int round = 0; round < 2; ++round) {
    EXPECT_EQ(run(0, n, 1.0f), expected(n)) << "variant 0, round " << round;
    EXPECT_EQ(run(1, m, 1.0f), expected(m)) << "variant 1, round " << round;
    EXPECT_EQ(run(1, m, 0.0f), input) << "variant 1 closed, round " << round;
  }
  EXPECT_EQ(gate.readOpened(), 4u);
  rec.begin();
  rec.beginGate(gate, 1);
  EXPECT_THROW(scan.record(rec, n), std::logic_error);  // variant 1 was recorded with m
  rec.endGate();
  EXPECT_THROW(rec.beginGate(gate, 2), std::out_of_range);
  EXPECT_THROW(rec.endGate(), std::logic_error);  // the failed begin opened no region
  rec.end();
}

}  // namespace
}  // namespace hemo::test
