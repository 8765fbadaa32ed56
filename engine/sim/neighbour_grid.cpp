#include "hemo/sim/neighbour_grid.hpp"

#include "hemo/gpu/pipeline_cache.hpp"
#include "interface/grid.h"
#include "interface/scan.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace hemo::sim {

namespace {
constexpr std::uint32_t kWorkgroup = 256;
// grid/cell_scan.comp: a workgroup scans kScanBlock keys.
constexpr std::uint32_t kScanWorkgroup = 256;
constexpr std::uint32_t kScanBlock = kScanWorkgroup * HEMO_SCAN_ITEMS;
static_assert(kScanBlock % 4 == 0, "grid/scatter.comp writes four entries of one block per texel");
std::uint64_t ceilDivKeys(std::uint64_t keys) { return (keys + kScanBlock - 1) / kScanBlock; }
// Entries of the per-key buffers: cellStart's keyCount + 1, padded to whole uvec4 texels (the
// scan and the scatter read and write four at a time).
std::uint64_t keyEntries(const GridSpec& spec) { return (spec.keyCount() + 1 + 3) / 4 * 4; }

struct CellScanPush {
  std::uint32_t keys;
};

struct ScatterPush {
  std::uint32_t n;
  std::uint32_t keys;
  std::uint32_t blockSize;
};
static_assert(sizeof(ScatterPush) == 12);

struct CountPush {
  std::uint32_t n;
};

struct ReorderPush {
  std::uint32_t n;
  std::uint32_t idCapacity;
};
static_assert(sizeof(ReorderPush) == 8);

struct NeighbourListPush {
  NeighbourGrid::Push grid;
  float radius;
  std::uint32_t capacity;
  std::uint32_t pad[2];
};
static_assert(sizeof(NeighbourListPush) == 80);
}  // namespace

void GridSpec::validate() const {
  if (!std::isfinite(cellSize) || cellSize <= 0.0f) {
    throw std::invalid_argument("grid cell size must be a positive finite length in m, got " + std::to_string(cellSize));
  }
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(cellScale[a]) || cellScale[a] < 1.0f) {
      throw std::invalid_argument(std::string("grid cell scale along ") + "xyz"[a] + " must be finite and >= 1, got " +
                                  std::to_string(cellScale[a]));
    }
  }
  if (!std::isfinite(origin.x) || !std::isfinite(origin.y) || !std::isfinite(origin.z)) {
    throw std::invalid_argument("grid origin must be finite");
  }
  if (dims.x == 0 || dims.y == 0 || dims.z == 0) {
    throw std::invalid_argument("grid needs at least one cell per axis");
  }
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(period[a]) || period[a] < 0.0f) throw std::invalid_argument("grid period must be finite and >= 0");
    if (periodic(a) && dims[a] < 3) {
      throw std::invalid_argument(std::string("periodic axis ") + "xyz"[a] + " of " + std::to_string(period[a]) +
                                  " m holds only " + std::to_string(dims[a]) + " cells of " + std::to_string(cellSize * cellScale[a]) +
                                  " m; it needs at least 3 (a period of at least " + std::to_string(3.0f * cellSize * cellScale[a]) +
                                  " m)");
    }
  }
  if (parts != 1 && parts != 2) {
    throw std::invalid_argument("grid parts must be 1 or 2, got " + std::to_string(parts));
  }
  // cellStart has keyCount + 1 entries and keys must fit in uint32.
  if (keyCount() >= 0xffffffffull) {
    throw std::invalid_argument("grid of " + std::to_string(dims.x) + "x" + std::to_string(dims.y) + "x" +
                                std::to_string(dims.z) + " cells is too large for 32-bit cell indices");
  }
}

glm::vec3 GridSpec::invCellSize() const {
  glm::vec3 inv;
  for (int a = 0; a < 3; ++a) inv[a] = periodic(a) ? float(double(dims[a]) / period[a]) : 1.0f / (cellSize * cellScale[a]);
  return inv;
}

GridSpec GridSpec::covering(glm::vec3 lo, glm::vec3 hi, float cellSize, glm::bvec3 periodic, glm::vec3 cellScale) {
  GridSpec spec;
  spec.origin = lo;
  spec.cellSize = cellSize;
  spec.cellScale = cellScale;
  if (!(cellSize > 0.0f) || !std::isfinite(cellSize) || !(glm::all(glm::greaterThanEqual(cellScale, glm::vec3(1.0f))))) {
    spec.validate();  // throws with the message about the cell size or scale
  }
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(lo[a]) || !std::isfinite(hi[a]) || hi[a] < lo[a]) {
      throw std::invalid_argument("grid bounds must be finite with min <= max on every axis");
    }
    const double extent = double(hi[a]) - lo[a];
    const double size = double(cellSize) * cellScale[a];
    const double cells = periodic[a] ? std::floor(extent / size) : std::ceil(extent / size);
    if (cells > 4.0e9) throw std::invalid_argument("grid bounds span too many cells");
    spec.dims[a] = static_cast<std::uint32_t>(std::max(periodic[a] ? 0.0 : 1.0, cells));
    if (periodic[a]) spec.period[a] = float(extent);
  }
  spec.validate();
  return spec;
}

NeighbourGrid::NeighbourGrid(gpu::Context& context, const GridSpec& spec, ParticleStore& particles)
    : spec_(spec),
      particles_(&particles),
      pairs_(context, std::uint64_t(std::max(particles.capacity(), 1u)) * 8, gpu::MemoryUse::Device, "grid pairs"),
      order_(context, std::uint64_t(std::max(particles.capacity(), 1u)) * 8, gpu::MemoryUse::Device, "grid order"),
      keyCounts_(context, keyEntries(spec) * 4, gpu::MemoryUse::Device, "grid key counts"),
      keyLocal_(context, keyEntries(spec) * 4, gpu::MemoryUse::Device, "grid key offsets in block"),
      blocks_(context, std::max<std::uint64_t>(ceilDivKeys(spec.keyCount() + 1), 1) * 4, gpu::MemoryUse::Device,
              "grid block offsets"),
      finished_(context, 16, gpu::MemoryUse::Device, "grid scan workgroups finished"),
      cellStart_(context, keyEntries(spec) * 4, gpu::MemoryUse::Device, "grid cellStart"),
      counters_(context, HEMO_COUNTER_COUNT * 4, gpu::MemoryUse::Device, "grid counters"),
      slotOfId_(context, std::uint64_t(std::max(particles.capacity(), 1u)) * 4, gpu::MemoryUse::Device, "slot of id"),
      posAtBuild_(context, std::uint64_t(std::max(particles.capacity(), 1u)) * 16, gpu::MemoryUse::Device,
                  "positions at the last grid build") {
  spec_.validate();
  // The counts start at zero, and every build's scatter leaves them at zero again; the scan's
  // finished-workgroup counter likewise.
  keyCounts_.upload(std::vector<std::uint32_t>(keyEntries(spec_), 0u));
  // (cellStart's padding is only ever copied back by the scatter, but defined all the same)
  cellStart_.upload(std::vector<std::uint32_t>(keyEntries(spec_), 0u));
  finished_.upload(std::vector<std::uint32_t>(4, 0u));
  // Read-only inputs are texel slots (gpu/pipeline.hpp, texelSlots): llvmpipe reads a storage
  // buffer lane by lane.
  hash_ = &context.pipelines().get({"grid/hash", HEMO_HASH_BINDING_COUNT, sizeof(Push), kWorkgroup, {}, 0u,
                                    1u << HEMO_HASH_BINDING_POSITIONS | 1u << HEMO_HASH_BINDING_VELOCITIES |
                                        1u << HEMO_HASH_BINDING_NORMALS | 1u << HEMO_HASH_BINDING_IDS});
  cellScan_ = &context.pipelines().get({"grid/cell_scan", HEMO_CELL_SCAN_BINDING_COUNT, sizeof(CellScanPush),
                                        kScanWorkgroup, {}, 0u, 1u << HEMO_CELL_SCAN_BINDING_KEY_COUNTS});
  scatter_ = &context.pipelines().get({"grid/scatter", HEMO_SCATTER_BINDING_COUNT, sizeof(ScatterPush), kWorkgroup, {},
                                       0u,
                                       1u << HEMO_SCATTER_BINDING_PAIRS | 1u << HEMO_SCATTER_BINDING_LOCAL |
                                           1u << HEMO_SCATTER_BINDING_BLOCKS | 1u << HEMO_SCATTER_BINDING_CELL_START_IN});
  reorder_ = &context.pipelines().get({"grid/reorder", HEMO_REORDER_BINDING_COUNT, sizeof(ReorderPush), kWorkgroup, {}, 0u,
                                       1u << HEMO_REORDER_BINDING_ORDER | 1u << HEMO_REORDER_BINDING_CELL_START |
                                           1u << HEMO_REORDER_BINDING_POS_IN | 1u << HEMO_REORDER_BINDING_VEL_IN |
                                           1u << HEMO_REORDER_BINDING_ID_IN | 1u << HEMO_REORDER_BINDING_NORMAL_IN});
  const ParticleArrays& live = particles.live();
  const ParticleArrays& scratch = particles.scratch();
  hashSet_ = hash_->makeSet({gpu::texelBinding(HEMO_HASH_BINDING_POSITIONS, &live.positions, gpu::texel::kVec4),
                             gpu::texelBinding(HEMO_HASH_BINDING_VELOCITIES, &live.velocities, gpu::texel::kVec4),
                             {HEMO_HASH_BINDING_PAIRS, &pairs_},
                             {HEMO_HASH_BINDING_COUNTERS, &counters_},
                             {HEMO_HASH_BINDING_KEY_COUNTS, &keyCounts_},
                             gpu::texelBinding(HEMO_HASH_BINDING_NORMALS, &live.normals, gpu::texel::kVec4),
                             gpu::texelBinding(HEMO_HASH_BINDING_IDS, &live.ids, gpu::texel::kUint),
                             {HEMO_HASH_BINDING_POS_OUT, &scratch.positions},
                             {HEMO_HASH_BINDING_VEL_OUT, &scratch.velocities},
                             {HEMO_HASH_BINDING_NORMAL_OUT, &scratch.normals},
                             {HEMO_HASH_BINDING_ID_OUT, &scratch.ids}});
  cellScanSet_ = cellScan_->makeSet({gpu::texelBinding(HEMO_CELL_SCAN_BINDING_KEY_COUNTS, &keyCounts_, gpu::texel::kUvec4),
                                     {HEMO_CELL_SCAN_BINDING_LOCAL, &keyLocal_},
                                     {HEMO_CELL_SCAN_BINDING_BLOCKS, &blocks_},
                                     {HEMO_CELL_SCAN_BINDING_FINISHED, &finished_}});
  scatterSet_ = scatter_->makeSet({gpu::texelBinding(HEMO_SCATTER_BINDING_PAIRS, &pairs_, gpu::texel::kUvec2),
                                   gpu::texelBinding(HEMO_SCATTER_BINDING_LOCAL, &keyLocal_, gpu::texel::kUvec4),
                                   gpu::texelBinding(HEMO_SCATTER_BINDING_BLOCKS, &blocks_, gpu::texel::kUint),
                                   {HEMO_SCATTER_BINDING_CELL_START, &cellStart_},
                                   {HEMO_SCATTER_BINDING_ORDER, &order_},
                                   {HEMO_SCATTER_BINDING_KEY_COUNTS, &keyCounts_},
                                   gpu::texelBinding(HEMO_SCATTER_BINDING_CELL_START_IN, &cellStart_, gpu::texel::kUvec4)});
  reorderSet_ = reorder_->makeSet({gpu::texelBinding(HEMO_REORDER_BINDING_ORDER, &order_, gpu::texel::kUvec2),
                                   gpu::texelBinding(HEMO_REORDER_BINDING_CELL_START, &cellStart_, gpu::texel::kUint),
                                   gpu::texelBinding(HEMO_REORDER_BINDING_POS_IN, &scratch.positions, gpu::texel::kVec4),
                                   gpu::texelBinding(HEMO_REORDER_BINDING_VEL_IN, &scratch.velocities, gpu::texel::kVec4),
                                   gpu::texelBinding(HEMO_REORDER_BINDING_ID_IN, &scratch.ids, gpu::texel::kUint),
                                   {HEMO_REORDER_BINDING_POS_OUT, &live.positions},
                                   {HEMO_REORDER_BINDING_VEL_OUT, &live.velocities},
                                   {HEMO_REORDER_BINDING_ID_OUT, &live.ids},
                                   {HEMO_REORDER_BINDING_SLOT_OF_ID, &slotOfId_},
                                   gpu::texelBinding(HEMO_REORDER_BINDING_NORMAL_IN, &scratch.normals, gpu::texel::kVec4),
                                   {HEMO_REORDER_BINDING_NORMAL_OUT, &live.normals},
                                   {HEMO_REORDER_BINDING_POS_AT_BUILD, &posAtBuild_}});
}

NeighbourGrid::Push NeighbourGrid::push(std::uint32_t n) const {
  const glm::vec3 inv = spec_.invCellSize();
  return Push{{spec_.origin.x, spec_.origin.y, spec_.origin.z, 0.0f},
              {inv.x, inv.y, inv.z, 0.0f},
              {spec_.dims.x, spec_.dims.y, spec_.dims.z},
              n,
              {spec_.periodic(0) ? 1u : 0u, spec_.periodic(1) ? 1u : 0u, spec_.periodic(2) ? 1u : 0u, spec_.parts}};
}

void NeighbourGrid::resetCounters(gpu::CommandRecorder& rec) {
  rec.fill(counters_, 0);
  rec.transferToCompute();
}

void NeighbourGrid::record(gpu::CommandRecorder& rec, std::uint32_t n, std::uint32_t sorted,
                           gpu::TimestampQueries* timestamps) {
  auto mark = [&](const char* stage) {
    if (timestamps) timestamps->mark(rec, stage);
  };
  if (n > particles_->capacity()) {
    throw std::invalid_argument("neighbour grid: " + std::to_string(n) + " particles exceed the capacity " +
                                std::to_string(particles_->capacity()));
  }
  if (sorted > n || (sorted < n && spec_.parts != 2)) {
    throw std::invalid_argument("neighbour grid: a partial build (" + std::to_string(sorted) + " of " +
                                std::to_string(n) + " slots) needs a grid of two parts");
  }
  const std::uint32_t keys = static_cast<std::uint32_t>(spec_.keyCount() + 1);  // cellStart entries
  // A partial build scans part 0's counts only: its last entry, cellStart[cellCount], is the
  // number of slots sorted, which is where part 1 starts.
  const std::uint32_t keysSorted = sorted < n ? static_cast<std::uint32_t>(spec_.cellCount() + 1) : keys;
  // A counting sort (interface/grid.h): five dispatches in all with the reorder and the list
  // where the radix sort took eleven. (Inside the solver's rebuild gate, a step that skips
  // them pays about 1 us each on llvmpipe: dispatch_closed in hemo-bench primitives.)
  // Each pass is dispatched over what it sorts only: llvmpipe runs a SIMD group's code even
  // when none of its lanes has work (a solver that sorts only the moving slots records the
  // two shapes in two variants of its rebuild gate).
  rec.dispatch(*hash_, hashSet_, push(sorted), hash_->groupsFor(std::max(sorted, 1u)));
  rec.computeToCompute();
  mark("hash");
  rec.dispatch(*cellScan_, cellScanSet_, CellScanPush{keysSorted}, cellScan_->groupsFor(keysSorted, HEMO_SCAN_ITEMS));
  rec.computeToCompute();
  rec.dispatch(*scatter_, scatterSet_, ScatterPush{sorted, keysSorted, kScanBlock},
               scatter_->groupsFor(std::max<std::uint64_t>(sorted, (keysSorted + 3) / 4)));
  rec.computeToCompute();
  mark("sort");
  rec.dispatch(*reorder_, reorderSet_, ReorderPush{sorted, particles_->capacity()},
               reorder_->groupsFor(std::max(sorted, 1u)));
  rec.computeToCompute();
  mark("reorder");
}

void NeighbourGrid::checkpointBuffers(std::vector<gpu::Buffer*>& out) {
  out.insert(out.end(), {&pairs_, &order_, &keyCounts_, &keyLocal_, &blocks_, &finished_, &cellStart_, &counters_,
                         &slotOfId_, &posAtBuild_});
}

GridCounters NeighbourGrid::readCounters() const {
  const auto c = counters_.readback<std::uint32_t>(HEMO_COUNTER_COUNT);
  return GridCounters{c[HEMO_COUNTER_OUTSIDE], c[HEMO_COUNTER_NONFINITE]};
}

NeighbourList::NeighbourList(gpu::Context& context, const NeighbourGrid& grid, ParticleStore& particles,
                             float radius, std::uint32_t maxPerParticle)
    : grid_(&grid),
      radius_(radius),
      maxPerParticle_(maxPerParticle),
      counts_(context, std::uint64_t(std::max(particles.capacity(), 1u)) * 4, gpu::MemoryUse::Device,
              "neighbour counts"),
      list_(context, std::uint64_t(std::max(particles.capacity(), 1u)) * std::max(maxPerParticle, 1u) * 4,
            gpu::MemoryUse::Device, "neighbour list") {
  if (grid.spec().parts != 1) {
    throw std::invalid_argument("NeighbourList needs a grid of one part (GridSpec::parts = 1)");
  }
  if (!(radius > 0.0f) || radius > grid.spec().cellSize ||
      (grid.spec().periodic(0) && 2.0f * radius > grid.spec().period.x) ||
      (grid.spec().periodic(1) && 2.0f * radius > grid.spec().period.y) ||
      (grid.spec().periodic(2) && 2.0f * radius > grid.spec().period.z)) {
    throw std::invalid_argument("neighbour radius " + std::to_string(radius) +
                                " m must be positive and at most the grid cell size " +
                                std::to_string(grid.spec().cellSize) + " m");
  }
  pipeline_ = &context.pipelines().get(
      {"grid/neighbour_list", HEMO_NLIST_BINDING_COUNT, sizeof(NeighbourListPush), kWorkgroup, {}});
  set_ = pipeline_->makeSet({{HEMO_NLIST_BINDING_POSITIONS, &particles.live().positions},
                            {HEMO_NLIST_BINDING_CELL_START, &grid.cellStart()},
                            {HEMO_NLIST_BINDING_COUNTS, &counts_},
                            {HEMO_NLIST_BINDING_LIST, &list_}});
}

void NeighbourList::record(gpu::CommandRecorder& rec, std::uint32_t n) const {
  const NeighbourListPush push{grid_->push(n), radius_, maxPerParticle_, {0, 0}};
  rec.dispatch(*pipeline_, set_, push, pipeline_->groupsFor(n));
  rec.computeToCompute();
}

void NeighbourGrid::setUploadedSlots(const std::vector<std::uint32_t>& ids) {
  const std::size_t capacity = slotOfId_.size() / 4;
  std::vector<std::uint32_t> slots(capacity, 0u);
  for (std::size_t slot = 0; slot < ids.size(); ++slot) {
    if (ids[slot] < capacity) slots[ids[slot]] = static_cast<std::uint32_t>(slot);
  }
  slotOfId_.upload(slots);
}

}  // namespace hemo::sim
