// GPU neighbour grid against the CPU twin and an O(N^2) brute force.
#include "gpu_test.hpp"
#include "hemo/reference/neighbours.hpp"
#include "hemo/sim/neighbour_grid.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <memory>
#include <set>

namespace hemo::test {
namespace {

struct Result {
  std::vector<glm::vec4> positions;  // sorted
  std::vector<glm::vec4> velocities;
  std::vector<glm::vec4> normals;
  std::vector<std::uint32_t> ids;
  std::vector<std::uint32_t> cellStart;
  std::vector<std::uint32_t> slotOfId;
  std::vector<std::uint32_t> counts;
  std::vector<std::uint32_t> list;
  sim::GridCounters counters;
};

class NeighbourTest : public GpuTest {
 protected:
  static constexpr std::uint32_t kMaxNeighbours = 256;

  // kinds (velocities.w) of the particles: kindOf(i), 1 (boundary) for all without it. A grid of
  // two parts builds no list (NeighbourList needs one part).
  Result run(const sim::GridSpec& spec, const std::vector<glm::vec4>& pos, float radius, int builds = 1,
             const std::vector<float>& kinds = {}) {
    sim::ParticleStore store(ctx(), static_cast<std::uint32_t>(pos.size()));
    std::vector<glm::vec4> vel(pos.size());
    for (std::size_t i = 0; i < pos.size(); ++i) vel[i] = glm::vec4(float(i), -float(i), 0.5f, kindOf(i, kinds));
    // ids are a permutation so id != input slot
    std::vector<std::uint32_t> ids(pos.size());
    for (std::size_t i = 0; i < ids.size(); ++i) ids[i] = static_cast<std::uint32_t>(ids.size() - 1 - i);
    std::vector<glm::vec4> normals(pos.size());
    for (std::size_t i = 0; i < pos.size(); ++i) normals[i] = glm::vec4(0.0f, float(i), 1.0f, -float(i));
    store.upload(pos, vel, ids, normals);
    sim::NeighbourGrid grid(ctx(), spec, store);
    std::unique_ptr<sim::NeighbourList> nlist;
    if (spec.parts == 1) nlist = std::make_unique<sim::NeighbourList>(ctx(), grid, store, radius, kMaxNeighbours);
    gpu::CommandRecorder rec(ctx());
    rec.begin();
    grid.resetCounters(rec);
    for (int b = 0; b < builds; ++b) grid.record(rec, store.count());
    if (nlist) nlist->record(rec, store.count());
    rec.end();
    rec.submitAndWait();
    Result r;
    r.positions = store.readPositions();
    r.velocities = store.readVelocities();
    r.normals = store.readNormals();
    r.ids = store.readIds();
    r.cellStart = grid.cellStart().readback<std::uint32_t>(spec.keyCount() + 1);
    r.slotOfId = grid.slotOfId().readback<std::uint32_t>(pos.size());
    if (nlist) {
      r.counts = nlist->counts().readback<std::uint32_t>(pos.size());
      r.list = nlist->list().readback<std::uint32_t>(pos.size() * kMaxNeighbours);
    }
    r.counters = grid.readCounters();
    return r;
  }

  // Checks the neighbour sets (by input index) against brute force; pairs whose distance is
  // within float rounding of the radius may go either way.
  // Periodic axes (period != 0) use the minimum image; lists are ascending without them.
  void expectNeighboursMatch(const std::vector<glm::vec4>& pos, float radius, const Result& r,
                             glm::dvec3 period = glm::dvec3(0.0)) {
    const std::size_t n = pos.size();
    std::vector<glm::dvec3> dpos(n);
    for (std::size_t i = 0; i < n; ++i) dpos[i] = glm::dvec3(pos[i]);
    const auto brute = reference::neighboursBruteForce(dpos, radius, period);
    const bool ascending = period == glm::dvec3(0.0);
    // ids[slot] = n - 1 - input index
    auto inputOf = [&](std::uint32_t slot) { return static_cast<std::uint32_t>(n - 1 - r.ids[slot]); };
    std::size_t checked = 0;
    for (std::uint32_t slot = 0; slot < n; ++slot) {
      const std::uint32_t i = inputOf(slot);
      ASSERT_LE(r.counts[slot], kMaxNeighbours) << "test set too dense for the list capacity";
      std::set<std::uint32_t> got;
      for (std::uint32_t k = 0; k < r.counts[slot]; ++k) {
        const std::uint32_t j = r.list[slot * kMaxNeighbours + k];
        if (k > 0 && ascending) {
          ASSERT_LT(r.list[slot * kMaxNeighbours + k - 1], j) << "list not ascending";
        }
        got.insert(inputOf(j));
      }
      const std::set<std::uint32_t> want(brute[i].begin(), brute[i].end());
      std::vector<std::uint32_t> diff;
      std::set_symmetric_difference(got.begin(), got.end(), want.begin(), want.end(), std::back_inserter(diff));
      for (std::uint32_t j : diff) {
        glm::dvec3 sep = dpos[i] - dpos[j];
        for (int a = 0; a < 3; ++a) {
          if (period[a] > 0.0) sep[a] -= period[a] * std::round(sep[a] / period[a]);
        }
        EXPECT_NEAR(glm::length(sep), radius, 1e-5 * radius) << "particle " << i << " neighbour " << j << " differs";
      }
      checked += want.size();
    }
    EXPECT_GT(checked, 0u);
  }

  static float kindOf(std::size_t i, const std::vector<float>& kinds) { return i < kinds.size() ? kinds[i] : 1.0f; }

  // Sorted order = stable sort of the input by reference key (ties at cell faces excepted),
  // data moved with it, slotOfId consistent, cellStart matching.
  void expectGridMatchesReference(const sim::GridSpec& spec, const std::vector<glm::vec4>& pos, const Result& r,
                                  const std::vector<float>& kinds = {}) {
    const std::size_t n = pos.size();
    reference::Grid g{glm::dvec3(spec.origin), spec.cellSize, spec.dims, spec.parts};
    std::vector<glm::dvec3> dpos(n);
    std::vector<bool> fluid(n);
    for (std::size_t i = 0; i < n; ++i) {
      dpos[i] = glm::dvec3(pos[i]);
      fluid[i] = kindOf(i, kinds) == 0.0f;
    }
    const auto ref = reference::buildGrid(dpos, g, fluid);
    EXPECT_EQ(r.counters.outside, ref.outside);
    EXPECT_EQ(r.counters.nonFinite, 0u);
    EXPECT_EQ(r.cellStart.size(), ref.cellStart.size());
    EXPECT_EQ(r.cellStart, ref.cellStart);
    std::vector<bool> seen(n, false);
    for (std::uint32_t slot = 0; slot < n; ++slot) {
      const std::uint32_t i = static_cast<std::uint32_t>(n - 1 - r.ids[slot]);
      ASSERT_LT(i, n);
      EXPECT_FALSE(seen[i]) << "input particle " << i << " appears twice";
      seen[i] = true;
      EXPECT_EQ(r.positions[slot], pos[i]);
      EXPECT_EQ(r.velocities[slot], glm::vec4(float(i), -float(i), 0.5f, kindOf(i, kinds)));
      EXPECT_EQ(r.normals[slot], glm::vec4(0.0f, float(i), 1.0f, -float(i)));
      EXPECT_EQ(r.slotOfId[r.ids[slot]], slot);
      EXPECT_EQ(ref.order[slot], i) << "sorted slot " << slot;
    }
  }
};

std::vector<glm::vec4> uniformBox(std::mt19937_64& rng, std::size_t n, glm::vec3 lo, glm::vec3 hi) {
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<glm::vec4> p(n);
  for (auto& x : p) x = glm::vec4(lo + (hi - lo) * glm::vec3(u(rng), u(rng), u(rng)), 1.0f);
  return p;
}

// Coordinates snapped to multiples of 1/4096 m and cell sizes that are powers of two, so the
// cell of every particle is exact in float (GPU) and double (reference) alike.
std::vector<glm::vec4> snapped(std::vector<glm::vec4> p) {
  for (auto& x : p) x = glm::vec4(glm::round(glm::vec3(x) * 4096.0f) / 4096.0f, 1.0f);
  return p;
}

TEST_F(NeighbourTest, UniformParticlesMatchBruteForceAndReference) {
  auto rng = rngFor();
  const float h = 0.0625f;
  const auto spec = sim::GridSpec::covering({0, 0, 0}, {1.0f, 0.625f, 0.375f}, h);
  const auto pos = snapped(uniformBox(rng, 6000, {0, 0, 0}, {1.0f, 0.625f, 0.375f}));
  const Result r = run(spec, pos, h);
  expectGridMatchesReference(spec, pos, r);
  expectNeighboursMatch(pos, h, r);
}

// Periodic on every axis, with periods that are not whole numbers of the requested cell size
// (so periodic cells are wider) and one axis of exactly three cells: neighbour sets across
// every seam, including the split x rows, match the minimum-image brute force, and nothing
// counts as outside.
TEST_F(NeighbourTest, PeriodicAxesWrapNeighbourCellsAndDistances) {
  auto rng = rngFor();
  const float h = 0.0625f;
  const glm::vec3 hi(1.0f, 0.7f, 0.2f);  // 16, 11 and 3 cells of 0.0625, 0.0636 and 0.0667 m
  const auto spec = sim::GridSpec::covering({0, 0, 0}, hi, h, glm::bvec3(true));
  ASSERT_EQ(spec.dims, glm::uvec3(16, 11, 3));
  auto pos = uniformBox(rng, 5000, {0, 0, 0}, hi);
  const Result r = run(spec, pos, h);
  EXPECT_EQ(r.counters.outside, 0u);
  expectNeighboursMatch(pos, h, r, glm::dvec3(hi));
  // A particle a rounding error outside the period is wrapped, not clamped and counted.
  pos[0] = glm::vec4(-1e-6f, hi.y + 1e-6f, 0.1f, 1.0f);
  EXPECT_EQ(run(spec, pos, h).counters.outside, 0u);

  EXPECT_THROW(sim::GridSpec::covering({0, 0, 0}, {1.0f, 0.18f, 1.0f}, h, glm::bvec3(false, true, false)),
               std::invalid_argument);  // 2 cells: the cells around a cell would repeat
}

TEST_F(NeighbourTest, ClusteredParticlesMatchBruteForce) {
  auto rng = rngFor();
  const float h = 0.125f;
  const auto spec = sim::GridSpec::covering({-1, -1, -1}, {1, 1, 1}, h);
  std::vector<glm::vec4> pos;
  std::normal_distribution<float> g(0.0f, 0.08f);
  for (int c = 0; c < 5; ++c) {
    const glm::vec3 centre(-0.6f + 0.3f * c, 0.1f * c - 0.2f, 0.0f);
    for (int k = 0; k < 300; ++k) pos.emplace_back(centre + glm::vec3(g(rng), g(rng), g(rng)), 1.0f);
  }
  pos = snapped(pos);
  const Result r = run(spec, pos, h * 0.9f);
  expectGridMatchesReference(spec, pos, r);
  expectNeighboursMatch(pos, h * 0.9f, r);
}

TEST_F(NeighbourTest, AllParticlesInOneCell) {
  auto rng = rngFor();
  const float h = 1.0f;
  const auto spec = sim::GridSpec::covering({0, 0, 0}, {8, 8, 8}, h);
  const auto pos = snapped(uniformBox(rng, 90, {3.1f, 3.1f, 3.1f}, {3.9f, 3.9f, 3.9f}));
  const Result r = run(spec, pos, h);
  expectGridMatchesReference(spec, pos, r);
  expectNeighboursMatch(pos, h, r);
  const std::uint32_t cell = 3 + 8 * (3 + 8 * 3);
  EXPECT_EQ(r.cellStart[cell + 1] - r.cellStart[cell], 90u);
}

TEST_F(NeighbourTest, ParticlesOutsideTheGridAreClampedAndCounted) {
  auto rng = rngFor();
  const float h = 0.125f;
  const auto spec = sim::GridSpec::covering({0, 0, 0}, {1, 1, 1}, h);
  auto pos = uniformBox(rng, 3000, {-0.3f, -0.2f, -0.25f}, {1.3f, 1.2f, 1.1f});
  pos.emplace_back(1e30f, -1e30f, 5.0f, 1.0f);  // far away: must not overflow anything
  pos = snapped(pos);
  const Result r = run(spec, pos, h);
  expectGridMatchesReference(spec, pos, r);
  expectNeighboursMatch(pos, h, r);
  EXPECT_GT(r.counters.outside, 100u);
}

TEST_F(NeighbourTest, NonFiniteParticlesAreCountedNotWrittenOutOfBounds) {
  const auto spec = sim::GridSpec::covering({0, 0, 0}, {1, 1, 1}, 0.25f);
  std::vector<glm::vec4> pos = {{0.1f, 0.1f, 0.1f, 1}, {NAN, 0.5f, 0.5f, 1}, {0.5f, INFINITY, 0.5f, 1}, {0.9f, 0.9f, 0.9f, 1}};
  const Result r = run(spec, pos, 0.25f);
  EXPECT_EQ(r.counters.nonFinite, 2u);
  EXPECT_EQ(r.cellStart.back(), 4u);
}

TEST_F(NeighbourTest, RepeatedBuildsAreBitIdentical) {
  auto rng = rngFor();
  const float h = 0.05f;
  const auto spec = sim::GridSpec::covering({0, 0, 0}, {0.5f, 0.5f, 0.5f}, h);
  const auto pos = uniformBox(rng, 20000, {0, 0, 0}, {0.5f, 0.5f, 0.5f});
  const Result a = run(spec, pos, h);
  const Result b = run(spec, pos, h);
  EXPECT_EQ(a.ids, b.ids);
  EXPECT_EQ(a.counts, b.counts);
  // The entries each particle's count covers (the rest of a row is never written: comparing
  // it compared whatever the fresh memory held, which failed at random once buffers were
  // allocated in a different order).
  const auto used = [](const Result& r) {
    std::vector<std::uint32_t> entries;
    for (std::size_t slot = 0; slot < r.counts.size(); ++slot) {
      const std::uint32_t count = std::min(r.counts[slot], kMaxNeighbours);
      entries.insert(entries.end(), r.list.begin() + std::ptrdiff_t(slot * kMaxNeighbours),
                     r.list.begin() + std::ptrdiff_t(slot * kMaxNeighbours + count));
    }
    return entries;
  };
  EXPECT_EQ(used(a), used(b));
  // Building again from already-sorted data keeps the order (stable sort of sorted data).
  const Result twice = run(spec, pos, h, 2);
  EXPECT_EQ(twice.ids, a.ids);
  EXPECT_EQ(twice.positions, a.positions);
}

// A grid of two parts (the SPH solver's): fluid particles (kind 0) sort before all others,
// each part by cell, against the CPU twin; kinds 1 and 2 both go to the second part.
TEST_F(NeighbourTest, TwoPartsPutTheFluidFirst) {
  auto rng = rngFor();
  const float h = 0.0625f;
  auto spec = sim::GridSpec::covering({0, 0, 0}, {1.0f, 0.625f, 0.375f}, h);
  spec.parts = 2;
  const auto pos = snapped(uniformBox(rng, 5000, {-0.1f, 0, 0}, {1.0f, 0.625f, 0.375f}));
  std::vector<float> kinds(pos.size());
  std::uniform_int_distribution<int> kind(0, 2);
  std::size_t fluid = 0;
  for (float& k : kinds) {
    k = float(kind(rng));
    fluid += k == 0.0f ? 1 : 0;
  }
  const Result r = run(spec, pos, h, 1, kinds);
  ASSERT_EQ(r.cellStart.size(), 2 * spec.cellCount() + 1);
  expectGridMatchesReference(spec, pos, r, kinds);
  EXPECT_EQ(r.cellStart[spec.cellCount()], fluid);  // the second part starts after the fluid
  for (std::size_t slot = 0; slot < pos.size(); ++slot) {
    EXPECT_EQ(r.velocities[slot].w == 0.0f, slot < fluid) << "slot " << slot;
  }
  sim::ParticleStore store(ctx(), 10);
  sim::NeighbourGrid grid(ctx(), spec, store);
  EXPECT_THROW(sim::NeighbourList(ctx(), grid, store, h, 8), std::invalid_argument);  // one part only
  spec.parts = 3;
  EXPECT_THROW(spec.validate(), std::invalid_argument);
}

// A partial build (the fluid alone, as the solver's moving slots) scans part 0's entries four
// at a time (grid/cell_scan.comp, grid/scatter.comp): the texel of part 0's last entry also
// holds the first entries of part 1, which that build must leave as the last whole build set
// them. Boundary particles fill part 1's first cells, so those entries differ from part 0's
// last, and the partial build must agree with a whole build of the same positions.
TEST_F(NeighbourTest, APartialBuildKeepsTheFirstRangesOfTheSecondPart) {
  auto rng = rngFor();
  const float h = 0.0625f;
  auto spec = sim::GridSpec::covering({0, 0, 0}, {1.0f, 0.5f, 0.25f}, h);
  spec.parts = 2;
  ASSERT_EQ(spec.cellCount(), 512u);
  ASSERT_EQ((spec.cellCount() + 1) % 4, 1u);  // entry cellCount shares its texel with part 1's cells 0-2
  // (away from the first row of cells, y < h, which holds only the particles placed below)
  auto pos = snapped(uniformBox(rng, 3000, {0, h, 0}, {1.0f, 0.5f, 0.25f}));
  std::vector<float> kinds(pos.size());
  std::bernoulli_distribution isFluid(0.5);
  for (float& k : kinds) k = isFluid(rng) ? 0.0f : 1.0f;
  for (int c = 0; c < 3; ++c) {  // boundary particles in the first cells of part 1 as well
    for (int k = 0; k <= c; ++k) {
      pos.emplace_back((float(c) + 0.5f) * h, 0.5f * h, (0.25f + 0.25f * float(k)) * h, 1.0f);
      kinds.push_back(1.0f);
    }
  }
  const auto n = static_cast<std::uint32_t>(pos.size());
  const auto fluid = static_cast<std::uint32_t>(std::count(kinds.begin(), kinds.end(), 0.0f));
  sim::ParticleStore store(ctx(), n);
  std::vector<glm::vec4> vel(n);
  for (std::uint32_t i = 0; i < n; ++i) vel[i] = glm::vec4(0.0f, 0.0f, 0.0f, kinds[i]);
  std::vector<std::uint32_t> ids(n);
  for (std::uint32_t i = 0; i < n; ++i) ids[i] = i;
  store.upload(pos, vel, ids, std::vector<glm::vec4>(n, glm::vec4(0.0f)));
  sim::NeighbourGrid grid(ctx(), spec, store);
  auto build = [&](std::uint32_t sorted) {
    gpu::CommandRecorder rec(ctx());
    rec.begin();
    grid.resetCounters(rec);
    grid.record(rec, n, sorted);
    rec.end();
    rec.submitAndWait();
    return grid.cellStart().readback<std::uint32_t>(spec.keyCount() + 1);
  };
  build(n);  // the slots in grid order: the fluid first
  // The fluid moves (snapped, inside the box); the boundary particles stay.
  auto moved = store.readPositions();
  std::uniform_real_distribution<float> step(-0.1f, 0.1f);
  for (std::uint32_t slot = 0; slot < fluid; ++slot) {
    const glm::vec3 x = glm::clamp(glm::vec3(moved[slot]) + glm::vec3(step(rng), step(rng), step(rng)), glm::vec3(0.0f),
                                   glm::vec3(0.999f, 0.499f, 0.249f));
    moved[slot] = glm::vec4(glm::round(x * 4096.0f) / 4096.0f, 1.0f);
  }
  store.live().positions.upload(moved);
  const auto partial = build(fluid);
  const auto whole = build(n);
  const std::size_t part1 = spec.cellCount();
  EXPECT_EQ(partial[part1], fluid);
  EXPECT_EQ(partial[part1 + 1], fluid + 1);  // one boundary particle in part 1's cell 0
  EXPECT_EQ(partial[part1 + 2], fluid + 3);  // two in cell 1
  EXPECT_EQ(partial[part1 + 3], fluid + 6);  // three in cell 2
  EXPECT_EQ(partial, whole);
}

// The counting sort scans the keys in blocks of 4,096 (grid/cell_scan.comp) and the last
// workgroup adds the blocks up: a grid of 32,768 keys (two parts of 16,384 cells) takes eight
// blocks. Built twice in one recording, the second build must find the counts and the scan's
// workgroup counter back at zero (it re-sorts sorted data and must give the same result).
TEST_F(NeighbourTest, ManyCellsSpanSeveralScanBlocks) {
  auto rng = rngFor();
  const float h = 0.03125f;
  auto spec = sim::GridSpec::covering({0, 0, 0}, {1.0f, 1.0f, 0.5f}, h);
  spec.parts = 2;
  ASSERT_EQ(spec.keyCount(), 32768u);
  const auto pos = snapped(uniformBox(rng, 12000, {-0.05f, 0, 0}, {1.0f, 1.0f, 0.5f}));
  std::vector<float> kinds(pos.size());
  std::bernoulli_distribution fluid(0.6);
  for (float& k : kinds) k = fluid(rng) ? 0.0f : 2.0f;
  const Result once = run(spec, pos, h, 1, kinds);
  expectGridMatchesReference(spec, pos, once, kinds);
  const Result twice = run(spec, pos, h, 2, kinds);  // (the counters add up over both builds)
  EXPECT_EQ(twice.cellStart, once.cellStart);
  EXPECT_EQ(twice.ids, once.ids);
  EXPECT_EQ(twice.positions, once.positions);
  EXPECT_EQ(twice.slotOfId, once.slotOfId);
}

TEST_F(NeighbourTest, RejectsARadiusLargerThanTheCell) {
  const auto spec = sim::GridSpec::covering({0, 0, 0}, {1, 1, 1}, 0.1f);
  sim::ParticleStore store(ctx(), 10);
  sim::NeighbourGrid grid(ctx(), spec, store);
  EXPECT_THROW(sim::NeighbourList(ctx(), grid, store, 0.2f, 8), std::invalid_argument);
}

}  // namespace
}  // namespace hemo::test
