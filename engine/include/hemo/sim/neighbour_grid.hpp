#pragma once
// Cell-linked-list neighbour search built on the GPU:
//   hash ........ key of each particle: its cell, or with two parts (GridSpec::parts) its
//                 cell + part * cellCount, part 0 for fluid particles (kind 0 in
//                 velocities.w) and 1 for all others; and its rank from a count per key;
//                 the live particle arrays copied to scratch
//   sort ........ a counting sort: exclusive scan of the counts (cellStart; empty cells carry
//                 the running offset) and each particle to its key's range
//   reorder ..... each particle's place within its key by slot (so the sort is stable and
//                 the order deterministic); positions/velocities/normals/ids moved from
//                 scratch into cell order in the live arrays, the positions at this build
//                 kept, id -> slot map
// The cell size is the support radius (or more); neighbours within it lie in the 27 cells
// around a particle, scanned as nine contiguous x-rows.
#include "hemo/gpu/primitives.hpp"
#include "hemo/sim/particles.hpp"

#include <glm/vec3.hpp>
#include <glm/vector_relational.hpp>

#include <array>
#include <cstdint>
#include <vector>

namespace hemo::sim {

struct GridSpec {
  glm::vec3 origin{0.0f};  // m, corner of cell (0,0,0)
  float cellSize = 0.0f;   // m, on bounded axes; periodic axes have cells of period / dims >= this
  // Cells along axis a are cellSize * cellScale[a] wide (>= 1: cellSize is the narrowest).
  glm::vec3 cellScale{1.0f};
  glm::uvec3 dims{0u};     // cells per axis
  glm::vec3 period{0.0f};  // m on periodic axes (the grid spans exactly one period), 0 on bounded ones
  // 1: particles sorted by cell. 2: fluid particles first, by cell, then all others, by
  // cell, so the slots [0, fluid count) hold the fluid and a pass over the slots runs each
  // SIMD group over one kind (on lavapipe a group of mixed kinds idles the lanes that return
  // early); cellStart then has 2 cellCount + 1 entries, part p's cell c at p cellCount + c.
  std::uint32_t parts = 1;

  std::uint64_t cellCount() const { return std::uint64_t(dims.x) * dims.y * dims.z; }
  std::uint64_t keyCount() const { return cellCount() * parts; }  // cellStart has keyCount() + 1 entries
  bool periodic(int axis) const { return period[axis] > 0.0f; }
  glm::vec3 invCellSize() const;  // cells per m along each axis
  // Throws std::invalid_argument naming the problem (non-positive or non-finite size, a
  // cell scale below 1 or not finite, zero dims, too many cells for 32-bit indices, a
  // periodic axis of fewer than 3 cells, parts other than 1 or 2).
  void validate() const;
  // The smallest grid of cells of `cellSize` (times `cellScale` per axis) that covers the box
  // [lo, hi]; on the axes flagged `periodic`, [lo, hi) is one period, split into as many whole
  // cells of at least that size as fit (at least 3).
  static GridSpec covering(glm::vec3 lo, glm::vec3 hi, float cellSize, glm::bvec3 periodic = glm::bvec3(false),
                           glm::vec3 cellScale = glm::vec3(1.0f));
};

// Counters the hash stage accumulates (read back only when the caller asks).
struct GridCounters {
  std::uint32_t outside = 0;    // particles clamped into border cells
  std::uint32_t nonFinite = 0;  // particles with a NaN or infinite coordinate
};

class NeighbourGrid {
 public:
  NeighbourGrid(gpu::Context& context, const GridSpec& spec, ParticleStore& particles);

  // Records the whole build for the store's first n particles, which end up sorted by cell
  // in the store's live arrays. Counters are reset by resetCounters(). With `timestamps`,
  // marks "hash", "sort" and "reorder" after each stage.
  void record(gpu::CommandRecorder& rec, std::uint32_t n, gpu::TimestampQueries* timestamps = nullptr) {
    record(rec, n, n, timestamps);
  }
  // The same with only the first `sorted` slots rebuilt (sorted < n: a grid of two parts
  // whose slots [sorted, n) hold part 1 exactly as the last whole build left it, particles
  // that have not moved since, such as rigid boundaries): their cells' ranges and data stay
  // as they are. The workgroup counts are those of the whole build (a dispatch gate may hold
  // both kinds of build); the slots and cells past the part are left out by the shaders.
  void record(gpu::CommandRecorder& rec, std::uint32_t n, std::uint32_t sorted,
              gpu::TimestampQueries* timestamps = nullptr);
  void resetCounters(gpu::CommandRecorder& rec);

  const GridSpec& spec() const { return spec_; }
  const gpu::Buffer& cellStart() const { return cellStart_; }  // keyCount + 1 entries
  const gpu::Buffer& slotOfId() const { return slotOfId_; }    // id -> slot (ids < capacity)
  // Before the first build: the slot of each id where the particles were uploaded (ids[slot],
  // below the capacity), so that what reads the map between set-up and the first step (the
  // renderer's springs and wall surface) finds the particles. An upload; ids not listed map to
  // slot 0.
  void setUploadedSlots(const std::vector<std::uint32_t>& ids);
  const gpu::Buffer& counters() const { return counters_; }
  const gpu::Buffer& positionsAtBuild() const { return posAtBuild_; }  // vec4 per slot: (x, kind)
  GridCounters readCounters() const;
  // Its buffers, for a checkpoint (hemo/io/checkpoint.hpp).
  void checkpointBuffers(std::vector<gpu::Buffer*>& out);

  struct Push {  // mirrors HemoGrid in common/grid.glsl
    float origin[4];
    float invCell[4];
    std::uint32_t dims[3];
    std::uint32_t n;
    std::uint32_t periodic[4];  // xyz: periodic axes; w: GridSpec::parts
  };
  static_assert(sizeof(Push) == 64);
  Push push(std::uint32_t n) const;

 private:
  GridSpec spec_;
  ParticleStore* particles_;
  const gpu::ComputePipeline* hash_;
  const gpu::ComputePipeline* cellScan_;
  const gpu::ComputePipeline* scatter_;
  const gpu::ComputePipeline* reorder_;
  gpu::Buffer pairs_;      // (key, rank) per slot
  gpu::Buffer order_;      // (key, source slot), in key order
  gpu::Buffer keyCounts_;  // zero between builds
  gpu::Buffer keyLocal_;   // exclusive scan within each block of keys
  gpu::Buffer blocks_;     // block offsets
  gpu::Buffer finished_;   // the scan's finished-workgroup counter (zero between builds)
  gpu::Buffer cellStart_;
  gpu::Buffer counters_;
  gpu::Buffer slotOfId_;
  gpu::Buffer posAtBuild_;
  gpu::DescriptorSet hashSet_, cellScanSet_, scatterSet_, reorderSet_;
};

// Every particle's neighbours closer than `radius` (<= cell size), as ascending slots of the
// sorted order, up to `maxPerParticle` each; counts() holds the true number (which may exceed
// the capacity: the caller checks). Record it after the grid build. Needs a grid of one part.
class NeighbourList {
 public:
  NeighbourList(gpu::Context& context, const NeighbourGrid& grid, ParticleStore& particles, float radius,
                std::uint32_t maxPerParticle);
  void record(gpu::CommandRecorder& rec, std::uint32_t n) const;
  const gpu::Buffer& counts() const { return counts_; }
  const gpu::Buffer& list() const { return list_; }
  std::uint32_t maxPerParticle() const { return maxPerParticle_; }

 private:
  const NeighbourGrid* grid_;
  const gpu::ComputePipeline* pipeline_;
  float radius_;
  std::uint32_t maxPerParticle_;
  gpu::Buffer counts_;
  gpu::Buffer list_;
  gpu::DescriptorSet set_;
};

}  // namespace hemo::sim
