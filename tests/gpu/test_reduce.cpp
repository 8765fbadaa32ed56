// Min/max reduction against std::minmax_element.
#include "gpu_test.hpp"
#include "hemo/gpu/primitives.hpp"

#include <glm/vec2.hpp>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>

namespace hemo::test {
namespace {

class ReduceTest : public GpuTest {
 protected:
  glm::vec2 gpuMinMax(const std::vector<float>& values) {
    gpu::Buffer data(ctx(), values.size() * 4, gpu::MemoryUse::Device, "values");
    data.upload(values);
    gpu::MinMaxReduce reduce(ctx(), data, values.size());
    gpu::CommandRecorder rec(ctx());
    rec.begin();
    reduce.record(rec, values.size());
    rec.end();
    rec.submitAndWait();
    return reduce.result().readback<glm::vec2>(1)[0];
  }
};

TEST_F(ReduceTest, MatchesMinMaxElementOnAwkwardSizes) {
  auto rng = rngFor();
  std::normal_distribution<float> dist(0.0f, 1e3f);
  for (std::size_t n : {1u, 2u, 63u, 64u, 65u, 2047u, 2048u, 2049u, 100003u, 4194319u}) {
    std::vector<float> v(n);
    for (auto& x : v) x = dist(rng);
    const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
    const glm::vec2 got = gpuMinMax(v);
    EXPECT_EQ(got.x, *lo) << "n = " << n;
    EXPECT_EQ(got.y, *hi) << "n = " << n;
  }
}

TEST_F(ReduceTest, EmptyGivesInfinities) {
  const glm::vec2 got = gpuMinMax({});
  EXPECT_EQ(got.x, std::numeric_limits<float>::infinity());
  EXPECT_EQ(got.y, -std::numeric_limits<float>::infinity());
}

TEST_F(ReduceTest, InfinitiesAreOrdinaryValues) {
  std::vector<float> v(3000, 1.0f);
  v[5] = -std::numeric_limits<float>::infinity();
  v[2999] = std::numeric_limits<float>::infinity();
  const glm::vec2 got = gpuMinMax(v);
  EXPECT_EQ(got.x, v[5]);
  EXPECT_EQ(got.y, v[2999]);
}

TEST_F(ReduceTest, AnyNanPoisonsTheResult) {
  for (std::size_t where : {0u, 1234u, 99999u}) {
    std::vector<float> v(100000, 2.0f);
    v[where] = std::numeric_limits<float>::quiet_NaN();
    const glm::vec2 got = gpuMinMax(v);
    EXPECT_TRUE(std::isnan(got.x) && std::isnan(got.y)) << "NaN at " << where;
  }
}

// One reducer recorded many times in one command buffer, on changing data and sizes: the
// finished-workgroup counter of the single-dispatch reduction must be back at 0 after every
// use, and a smaller n must not see an earlier run's partials.
TEST_F(ReduceTest, OneReducerRecordedManyTimesInACommandBuffer) {
  auto rng = rngFor();
  std::normal_distribution<float> dist(0.0f, 1.0f);
  const std::size_t capacity = 300007;
  const std::size_t sizes[] = {300007, 5000, 2049, 300007, 1, 70000};
  constexpr std::size_t kRuns = std::size(sizes);
  gpu::Buffer data(ctx(), capacity * 4, gpu::MemoryUse::Device, "values");
  gpu::Buffer sources(ctx(), kRuns * capacity * 4, gpu::MemoryUse::Device, "sources");
  gpu::Buffer results(ctx(), kRuns * 8, gpu::MemoryUse::Device, "results");
  std::vector<float> all(kRuns * capacity);
  for (auto& x : all) x = dist(rng);
  sources.upload(all);
  gpu::MinMaxReduce reduce(ctx(), data, capacity);
  gpu::CommandRecorder rec(ctx());
  rec.begin();
  for (std::size_t k = 0; k < kRuns; ++k) {
    rec.computeToTransfer();
    rec.copy(sources, data, capacity * 4, k * capacity * 4, 0);
    rec.transferToCompute();
    reduce.record(rec, sizes[k]);
    rec.computeToTransfer();
    rec.copy(reduce.result(), results, 8, 0, k * 8);
  }
  rec.end();
  rec.submitAndWait();
  const auto got = results.readback<glm::vec2>(kRuns);
  for (std::size_t k = 0; k < kRuns; ++k) {
    const auto first = all.begin() + std::ptrdiff_t(k * capacity);
    const auto [lo, hi] = std::minmax_element(first, first + std::ptrdiff_t(sizes[k]));
    EXPECT_EQ(got[k].x, *lo) << "run " << k << ", n = " << sizes[k];
    EXPECT_EQ(got[k].y, *hi) << "run " << k << ", n = " << sizes[k];
  }
}

}  // namespace
}  // namespace hemo::test
