#pragma once
// The blood surface on the GPU (compute_shaders/mc/), in the order it is recorded:
//   bounds ..... (ParticleField) the fluid's bounding box -> a grid of cubic voxels
//   splat ...... (ParticleField) the SPH volume fraction at the grid points, fixed point
//                (indirect: one invocation per particle and z-plane of its support), on the
//                extraction grid or on a coarser one
//   upsample ... (ParticleField, with a coarser splat grid) trilinear interpolation onto the
//                extraction grid
//   prepare .... runs of voxels and the classify dispatch (indirect)
//   classify ... per run of 4 voxels: cases, triangle count, active flag
//   scan ....... prefix sums of triangle counts and of active flags, over the grid's runs (a
//                length the GPU wrote: PrefixScan::recordGpuLength)
//   compact .... active runs in order; generate dispatch, draw arguments and totals
//   generate ... one invocation per voxel of each active run: its triangles (position +
//                normal per vertex) at their scanned offsets
// Every count stays on the GPU: the renderer draws with vkCmdDrawIndirect from args(), and
// the host reads totals or the mesh only when it writes a file. Deterministic: the splat adds
// integers, everything else is a gather. The CPU twin is hemo/reference/marching_cubes.hpp.
#include "hemo/gpu/primitives.hpp"
#include "hemo/sim/particles.hpp"
#include "hemo/surface/case_table.hpp"

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <cstdint>
#include <vector>

namespace hemo::surface {

// Mirror of McGrid (compute_shaders/common/mc.glsl).
struct McGrid {
  float origin[4];           // xyz m, w voxel size m
  std::uint32_t points[4];   // xyz per axis, w row stride (x padded to a multiple of 4)
  std::uint32_t runs[4];     // written by mc/prepare.comp
  float level[4];            // x iso
};
static_assert(sizeof(McGrid) == 64);

// Totals of the last extraction (interface/mc.h, McArgs).
struct McTotals {
  std::uint32_t triangles = 0;  // triangles the field holds
  std::uint32_t written = 0;    // triangles in vertices() (<= the capacity)
  std::uint32_t activeRuns = 0;
  std::uint32_t runs = 0;
  bool overflow() const { return written < triangles; }
};

// One vertex as the GPU writes it.
struct McVertex {
  glm::vec4 position;  // xyz m, w 1
  glm::vec4 normal;    // xyz unit (outward: down the field), w 0
};
static_assert(sizeof(McVertex) == 32);

struct SurfaceMesh {
  std::vector<McVertex> vertices;  // 3 per triangle
  McTotals totals;
  McGrid grid{};
};

// Field value (dimensionless) <-> fixed point, as the shaders store it.
std::int32_t toFixed(double value);
double fromFixed(std::int32_t value);

class MarchingCubes {
 public:
  // Buffers for grids of up to `maxVoxelsPerAxis` voxels along each axis and `maxTriangles`
  // triangles (0: 12 maxVoxelsPerAxis^2, enough for a few times the area of the grid's
  // inscribed sphere). Throws std::invalid_argument for a zero size and gpu::GpuError when
  // the buffers exceed the device.
  MarchingCubes(gpu::Context& context, std::uint32_t maxVoxelsPerAxis, std::uint32_t maxTriangles = 0);

  // Extracts the surface of field() on grid() (both written before: by ParticleField, or by
  // uploadField). Records transfer and compute commands and ends with a computeToCompute
  // barrier; a renderer adds computeToGraphics before it draws (readback: CommandRecorder::end
  // adds the barrier to the host).
  void record(gpu::CommandRecorder& rec, gpu::TimestampQueries* timestamps = nullptr) const;

  // Set-up/test path: a field given at the points of a grid (x fastest). Throws
  // std::invalid_argument when the grid exceeds the capacity or the values do not match it.
  void uploadField(glm::dvec3 origin, double voxel, glm::uvec3 points, const std::vector<double>& values, float iso);

  std::uint32_t maxVoxelsPerAxis() const { return maxVoxels_; }
  std::uint32_t maxTriangles() const { return maxTriangles_; }
  const gpu::Buffer& grid() const { return grid_; }
  const gpu::Buffer& field() const { return field_; }  // int32 fixed point per point, rows padded
  const gpu::Buffer& args() const { return args_; }    // McArgs (indirect dispatch + draw)
  const gpu::Buffer& vertices() const { return vertices_; }
  static constexpr VkDeviceSize drawArgsOffset() { return 8 * sizeof(std::uint32_t); }

  // Readbacks (outside any loop): totals and grid of the last extraction, and the mesh.
  McTotals readTotals() const;
  McGrid readGrid() const;
  SurfaceMesh readMesh() const;
  std::vector<std::int32_t> readField() const;  // without the row padding, x fastest

 private:
  gpu::Context* context_;
  std::uint32_t maxVoxels_;
  std::uint32_t maxTriangles_;
  std::uint64_t maxPoints_, maxRuns_;
  const gpu::ComputePipeline* prepare_;
  const gpu::ComputePipeline* classify_;
  const gpu::ComputePipeline* compact_;
  const gpu::ComputePipeline* generate_;
  gpu::Buffer grid_, field_, table_, runTriangles_, runActive_, runCases_, activeRuns_, args_, vertices_;
  gpu::PrefixScan triangleScan_, activeScan_;
  gpu::DescriptorSet prepareSet_, classifySet_, compactSet_, generateSet_;
};

// The fluid's field on a grid around it (mc/bounds.comp, mc/splat.comp), written into a
// MarchingCubes' grid and field. Reads a particle store in any order and the densities in
// `state` (vec4 (rho, ...) per slot, as sim::SphSolver::state()).
struct FieldSettings {
  std::uint32_t resolution = 128;  // voxels along the longest side of the grid
  float iso = 0.5f;                // surface where phi = iso
  float h = 0.0f;                  // smoothing length (m)
  float restDensity = 1000.0f;     // kg/m^3, for particles whose density is not known yet
  // > 0: splat on a grid of this voxel (in units of h; never finer than the extraction grid)
  // and interpolate the extraction grid's values from it (mc/upsample.comp), so the splat's
  // cost no longer grows with the cube of the extraction resolution. 0: splat directly on the
  // extraction grid.
  float splatVoxelOverH = 0.0f;
  // The grid stays inside this box (m): fluid that has flown far away is left out rather than
  // stretching the grid.
  glm::vec3 clipLo{-3.0e38f};
  glm::vec3 clipHi{3.0e38f};
};

class ParticleField {
 public:
  ParticleField(gpu::Context& context, MarchingCubes& target, const sim::ParticleStore& particles,
                const gpu::Buffer& state, const FieldSettings& settings);
  // Records bounds, clear and splat for the store's first n particles.
  void record(gpu::CommandRecorder& rec, std::uint32_t n, gpu::TimestampQueries* timestamps = nullptr) const;
  const FieldSettings& settings() const { return settings_; }
  // The grid the splat wrote on (the extraction grid's parameters when direct), for tests.
  McGrid readSplatGrid() const { return splatGrid_.readback<McGrid>(1)[0]; }

 private:
  MarchingCubes* target_;
  FieldSettings settings_;
  const gpu::ComputePipeline* bounds_;
  const gpu::ComputePipeline* splat_;
  const gpu::ComputePipeline* upsample_;
  gpu::Buffer splatArgs_, upsampleArgs_, splatGrid_, splatField_;
  gpu::DescriptorSet boundsSet_, splatSet_, upsampleSet_;
};

}  // namespace hemo::surface
