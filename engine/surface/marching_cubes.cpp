#include "hemo/surface/marching_cubes.hpp"

#include "hemo/gpu/pipeline_cache.hpp"
#include "interface/mc.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

namespace hemo::surface {
namespace {

constexpr std::uint32_t kWorkgroup = 64;  // classify, compact, generate, splat
constexpr std::uint32_t kBoundsWorkgroup = 256;
constexpr std::uint32_t kRun = HEMO_MC_RUN;
constexpr VkDeviceSize kArgsBytes = 16 * sizeof(std::uint32_t);

struct PreparePush {
  std::uint32_t classifyWorkgroup, maxRuns;
};
struct CompactPush {
  std::uint32_t maxTriangles, generateWorkgroup;
};
struct GeneratePush {
  std::uint32_t maxTriangles;
};
struct BoundsPush {
  std::uint32_t n, resolution;
  float margin, iso;
  std::uint32_t splatWorkgroup;
  float splatVoxel;
  std::uint32_t upsampleWorkgroup, pad;
  float clipLo[4], clipHi[4];
};
static_assert(sizeof(BoundsPush) == 64);
struct SplatPush {
  std::uint32_t n;
  float h, kernelNorm, rho0;
};

std::uint32_t checkedVoxels(std::uint32_t v) {
  if (v == 0) throw std::invalid_argument("surface grid: the resolution must be at least 1 voxel");
  if (v > 1024) throw std::invalid_argument("surface grid: " + std::to_string(v) + " voxels per axis is more than 1024");
  return v;
}

std::uint64_t runsFor(std::uint64_t voxelsPerAxis) {
  return ((voxelsPerAxis + kRun - 1) / kRun) * voxelsPerAxis * voxelsPerAxis;
}

// Ints per x-row of the field (common/mc.glsl, hemo_mc_row_stride).
std::uint32_t rowStride(std::uint32_t points) { return (points + 3u) & ~3u; }

std::uint32_t defaultTriangles(std::uint32_t voxels, std::uint32_t requested) {
  if (requested) return requested;
  return std::uint32_t(std::min<std::uint64_t>(12ull * voxels * voxels, 1u << 22));
}

}  // namespace

std::int32_t toFixed(double value) {
  const double scaled = std::nearbyint(value * HEMO_MC_FIXED_SCALE);
  if (!(std::abs(scaled) < 2147483647.0)) {
    throw std::invalid_argument("surface field value " + std::to_string(value) + " is outside the fixed-point range");
  }
  return std::int32_t(scaled);
}

double fromFixed(std::int32_t value) { return double(value) / HEMO_MC_FIXED_SCALE; }

MarchingCubes::MarchingCubes(gpu::Context& context, std::uint32_t maxVoxelsPerAxis, std::uint32_t maxTriangles)
    : context_(&context),
      maxVoxels_(checkedVoxels(maxVoxelsPerAxis)),
      maxTriangles_(defaultTriangles(maxVoxels_, maxTriangles)),
      maxPoints_(std::uint64_t(rowStride(maxVoxels_ + 1)) * (maxVoxels_ + 1) * (maxVoxels_ + 1)),
      maxRuns_(runsFor(maxVoxels_)),
      grid_(context, sizeof(McGrid), gpu::MemoryUse::Device, "surface grid"),
      field_(context, maxPoints_ * 4, gpu::MemoryUse::Device, "surface field"),
      table_(context, 256 * 16, gpu::MemoryUse::Device, "surface case table"),
      runTriangles_(context, (maxRuns_ + 1) * 4, gpu::MemoryUse::Device, "surface run triangles"),
      runActive_(context, (maxRuns_ + 1) * 4, gpu::MemoryUse::Device, "surface run active"),
      runCases_(context, maxRuns_ * 4, gpu::MemoryUse::Device, "surface run cases"),
      activeRuns_(context, maxRuns_ * 4, gpu::MemoryUse::Device, "surface active runs"),
      args_(context, kArgsBytes, gpu::MemoryUse::Device, "surface indirect arguments"),
      vertices_(context, std::uint64_t(maxTriangles_) * 3 * sizeof(McVertex), gpu::MemoryUse::Device,
                "surface vertices"),
      triangleScan_(context, runTriangles_, maxRuns_ + 1, 0, &args_),
      activeScan_(context, runActive_, maxRuns_ + 1, 0, &args_) {
  table_.upload(packCaseTable(buildCaseTable()));
  McGrid empty{};
  grid_.uploadBytes(&empty, sizeof(empty));
  args_.upload(std::vector<std::uint32_t>(16, 0u));
  auto& cache = context.pipelines();
  prepare_ = &cache.get({"mc/prepare", HEMO_MC_PREPARE_BINDING_COUNT, sizeof(PreparePush), 64, {}});
  classify_ = &cache.get({"mc/classify", HEMO_MC_CLASSIFY_BINDING_COUNT, 0, kWorkgroup, {},
                          1u << HEMO_MC_CLASSIFY_BINDING_GRID,
                          1u << HEMO_MC_CLASSIFY_BINDING_FIELD | 1u << HEMO_MC_CLASSIFY_BINDING_TABLE});
  compact_ = &cache.get({"mc/compact", HEMO_MC_COMPACT_BINDING_COUNT, sizeof(CompactPush), kWorkgroup, {}});
  generate_ = &cache.get({"mc/generate", HEMO_MC_GENERATE_BINDING_COUNT, sizeof(GeneratePush), kWorkgroup, {},
                          1u << HEMO_MC_GENERATE_BINDING_GRID,
                          1u << HEMO_MC_GENERATE_BINDING_FIELD | 1u << HEMO_MC_GENERATE_BINDING_TABLE |
                              1u << HEMO_MC_GENERATE_BINDING_RUN_TRIANGLES | 1u << HEMO_MC_GENERATE_BINDING_RUN_CASES |
                              1u << HEMO_MC_GENERATE_BINDING_ACTIVE_RUNS});
  prepareSet_ = prepare_->makeSet({{HEMO_MC_PREPARE_BINDING_GRID, &grid_}, {HEMO_MC_PREPARE_BINDING_ARGS, &args_}});
  classifySet_ = classify_->makeSet({{HEMO_MC_CLASSIFY_BINDING_GRID, &grid_},
                                     gpu::texelBinding(HEMO_MC_CLASSIFY_BINDING_FIELD, &field_, gpu::texel::kIvec4),
                                     gpu::texelBinding(HEMO_MC_CLASSIFY_BINDING_TABLE, &table_, gpu::texel::kUvec4),
                                     {HEMO_MC_CLASSIFY_BINDING_RUN_TRIANGLES, &runTriangles_},
                                     {HEMO_MC_CLASSIFY_BINDING_RUN_ACTIVE, &runActive_},
                                     {HEMO_MC_CLASSIFY_BINDING_RUN_CASES, &runCases_},
                                     {HEMO_MC_CLASSIFY_BINDING_ARGS, &args_}});
  compactSet_ = compact_->makeSet({{HEMO_MC_COMPACT_BINDING_RUN_TRIANGLES, &runTriangles_},
                                   {HEMO_MC_COMPACT_BINDING_RUN_ACTIVE, &runActive_},
                                   {HEMO_MC_COMPACT_BINDING_ACTIVE_RUNS, &activeRuns_},
                                   {HEMO_MC_COMPACT_BINDING_ARGS, &args_}});
  generateSet_ = generate_->makeSet({{HEMO_MC_GENERATE_BINDING_GRID, &grid_},
                                     gpu::texelBinding(HEMO_MC_GENERATE_BINDING_FIELD, &field_, gpu::texel::kInt),
                                     gpu::texelBinding(HEMO_MC_GENERATE_BINDING_TABLE, &table_, gpu::texel::kUvec4),
                                     gpu::texelBinding(HEMO_MC_GENERATE_BINDING_RUN_TRIANGLES, &runTriangles_, gpu::texel::kUint),
                                     gpu::texelBinding(HEMO_MC_GENERATE_BINDING_RUN_CASES, &runCases_, gpu::texel::kUint),
                                     gpu::texelBinding(HEMO_MC_GENERATE_BINDING_ACTIVE_RUNS, &activeRuns_, gpu::texel::kUint),
                                     {HEMO_MC_GENERATE_BINDING_ARGS, &args_},
                                     {HEMO_MC_GENERATE_BINDING_VERTICES, &vertices_}});
}

void MarchingCubes::record(gpu::CommandRecorder& rec, gpu::TimestampQueries* timestamps) const {
  // Scans run over the whole capacity: entries past the grid's runs must be zero. (The
  // barrier orders the clears after any earlier extraction in the same command buffer.)
  rec.computeToTransfer();
  rec.fill(runTriangles_, 0u);
  rec.fill(runActive_, 0u);
  rec.fill(args_, 0u);
  rec.transferToCompute();
  rec.dispatch(*prepare_, prepareSet_, PreparePush{classify_->workgroupSize(), std::uint32_t(maxRuns_)},
               prepare_->groupsFor(1));
  rec.computeToCompute();
  rec.dispatchIndirect(*classify_, classifySet_, args_, HEMO_MC_ARGS_CLASSIFY * 4);
  rec.computeToCompute();
  if (timestamps) timestamps->mark(rec, "classify");
  // Over the grid's runs + 1 entries (entry `runs` becomes the total), a count only the GPU
  // knows (prepare wrote it).
  triangleScan_.recordGpuLength(rec, HEMO_MC_ARGS_RUNS, 1);
  activeScan_.recordGpuLength(rec, HEMO_MC_ARGS_RUNS, 1);
  rec.computeToCompute();
  if (timestamps) timestamps->mark(rec, "scan");
  rec.dispatchIndirect(*compact_, compactSet_, CompactPush{maxTriangles_, generate_->workgroupSize()}, args_,
                       HEMO_MC_ARGS_CLASSIFY * 4);
  rec.computeToCompute();
  if (timestamps) timestamps->mark(rec, "compact");
  rec.dispatchIndirect(*generate_, generateSet_, GeneratePush{maxTriangles_}, args_, HEMO_MC_ARGS_GENERATE * 4);
  rec.computeToCompute();
  if (timestamps) timestamps->mark(rec, "generate");
}

void MarchingCubes::uploadField(glm::dvec3 origin, double voxel, glm::uvec3 points, const std::vector<double>& values,
                                float iso) {
  for (int a = 0; a < 3; ++a) {
    if (points[a] > maxVoxels_ + 1) {
      throw std::invalid_argument("surface grid: " + std::to_string(points[a]) + " points along axis " +
                                  std::to_string(a) + " exceed the capacity of " + std::to_string(maxVoxels_ + 1));
    }
  }
  const std::uint64_t count = std::uint64_t(points.x) * points.y * points.z;
  if (values.size() != count) {
    throw std::invalid_argument("surface grid: " + std::to_string(values.size()) + " values for " +
                                std::to_string(count) + " points");
  }
  if (!(voxel > 0.0) || !std::isfinite(voxel)) throw std::invalid_argument("surface grid: the voxel size must be positive");
  const std::uint32_t stride = rowStride(points.x);
  std::vector<std::int32_t> fixed(std::size_t(stride) * points.y * points.z, 0);
  for (std::uint32_t row = 0; row < points.y * points.z; ++row) {
    for (std::uint32_t x = 0; x < points.x; ++x) fixed[std::size_t(row) * stride + x] = toFixed(values[std::size_t(row) * points.x + x]);
  }
  McGrid g{};
  g.origin[0] = float(origin.x);
  g.origin[1] = float(origin.y);
  g.origin[2] = float(origin.z);
  g.origin[3] = float(voxel);
  g.points[0] = points.x;
  g.points[1] = points.y;
  g.points[2] = points.z;
  g.points[3] = stride;
  g.level[0] = iso;
  grid_.uploadBytes(&g, sizeof(g));
  field_.upload(fixed);
}

McTotals MarchingCubes::readTotals() const {
  const auto a = args_.readback<std::uint32_t>(16);
  McTotals t;
  t.triangles = a[HEMO_MC_ARGS_TRIANGLES];
  t.activeRuns = a[HEMO_MC_ARGS_ACTIVE_RUNS];
  t.written = a[HEMO_MC_ARGS_WRITTEN];
  t.runs = a[HEMO_MC_ARGS_RUNS];
  return t;
}

McGrid MarchingCubes::readGrid() const { return grid_.readback<McGrid>(1)[0]; }

SurfaceMesh MarchingCubes::readMesh() const {
  SurfaceMesh mesh;
  mesh.totals = readTotals();
  mesh.grid = readGrid();
  mesh.vertices = vertices_.readback<McVertex>(std::size_t(mesh.totals.written) * 3);
  return mesh;
}

std::vector<std::int32_t> MarchingCubes::readField() const {
  const McGrid g = readGrid();
  const std::size_t rows = std::size_t(g.points[1]) * g.points[2];
  const auto padded = field_.readback<std::int32_t>(rows * g.points[3]);
  std::vector<std::int32_t> values(rows * g.points[0]);
  for (std::size_t row = 0; row < rows; ++row) {
    std::copy_n(padded.begin() + std::ptrdiff_t(row * g.points[3]), g.points[0], values.begin() + std::ptrdiff_t(row * g.points[0]));
  }
  return values;
}

ParticleField::ParticleField(gpu::Context& context, MarchingCubes& target, const sim::ParticleStore& particles,
                             const gpu::Buffer& state, const FieldSettings& settings)
    : target_(&target),
      settings_(settings),
      splatArgs_(context, 16, gpu::MemoryUse::Device, "surface splat dispatch"),
      upsampleArgs_(context, 16, gpu::MemoryUse::Device, "surface upsample dispatch"),
      splatGrid_(context, sizeof(McGrid), gpu::MemoryUse::Device, "surface splat grid"),
      splatField_(context, settings.splatVoxelOverH > 0.0f ? target.field().size() : 16, gpu::MemoryUse::Device,
                  "surface splat field") {
  if (settings.resolution == 0 || settings.resolution > target.maxVoxelsPerAxis()) {
    throw std::invalid_argument("surface: resolution " + std::to_string(settings.resolution) +
                                " must be between 1 and the extractor's " + std::to_string(target.maxVoxelsPerAxis()));
  }
  if (!(settings.h > 0.0f) || !std::isfinite(settings.h)) throw std::invalid_argument("surface: h must be positive");
  if (!std::isfinite(settings.iso)) throw std::invalid_argument("surface: the iso level must be finite");
  if (!(settings.splatVoxelOverH >= 0.0f) || !std::isfinite(settings.splatVoxelOverH)) {
    throw std::invalid_argument("surface: the splat voxel (in h) must be >= 0");
  }
  for (int a = 0; a < 3; ++a) {
    if (!(settings.clipLo[a] < settings.clipHi[a])) throw std::invalid_argument("surface: an empty clip box");
  }
  auto& cache = context.pipelines();
  bounds_ = &cache.get({"mc/bounds", HEMO_MC_BOUNDS_BINDING_COUNT, sizeof(BoundsPush), kBoundsWorkgroup, {}, 0u,
                        1u << HEMO_MC_BOUNDS_BINDING_POSITIONS | 1u << HEMO_MC_BOUNDS_BINDING_VELOCITIES});
  splat_ = &cache.get({"mc/splat", HEMO_MC_SPLAT_BINDING_COUNT, sizeof(SplatPush), kWorkgroup, {},
                        1u << HEMO_MC_SPLAT_BINDING_GRID,
                        1u << HEMO_MC_SPLAT_BINDING_POSITIONS | 1u << HEMO_MC_SPLAT_BINDING_VELOCITIES |
                            1u << HEMO_MC_SPLAT_BINDING_STATE});
  upsample_ = &cache.get({"mc/upsample", HEMO_MC_UPSAMPLE_BINDING_COUNT, 0, kBoundsWorkgroup, {},
                           1u << HEMO_MC_UPSAMPLE_BINDING_GRID | 1u << HEMO_MC_UPSAMPLE_BINDING_SPLAT_GRID,
                           1u << HEMO_MC_UPSAMPLE_BINDING_SPLAT_FIELD});
  const bool coarse = settings.splatVoxelOverH > 0.0f;
  boundsSet_ = bounds_->makeSet({gpu::texelBinding(HEMO_MC_BOUNDS_BINDING_POSITIONS, &particles.live().positions, gpu::texel::kVec4),
                                 gpu::texelBinding(HEMO_MC_BOUNDS_BINDING_VELOCITIES, &particles.live().velocities, gpu::texel::kVec4),
                                 {HEMO_MC_BOUNDS_BINDING_GRID, &target.grid()},
                                 {HEMO_MC_BOUNDS_BINDING_SPLAT_ARGS, &splatArgs_},
                                 {HEMO_MC_BOUNDS_BINDING_SPLAT_GRID, &splatGrid_},
                                 {HEMO_MC_BOUNDS_BINDING_UPSAMPLE_ARGS, &upsampleArgs_}});
  splatSet_ = splat_->makeSet({gpu::texelBinding(HEMO_MC_SPLAT_BINDING_POSITIONS, &particles.live().positions, gpu::texel::kVec4),
                               gpu::texelBinding(HEMO_MC_SPLAT_BINDING_VELOCITIES, &particles.live().velocities, gpu::texel::kVec4),
                               gpu::texelBinding(HEMO_MC_SPLAT_BINDING_STATE, &state, gpu::texel::kVec4),
                               {HEMO_MC_SPLAT_BINDING_GRID, coarse ? &splatGrid_ : &target.grid()},
                               {HEMO_MC_SPLAT_BINDING_FIELD, coarse ? &splatField_ : &target.field()}});
  upsampleSet_ = upsample_->makeSet({{HEMO_MC_UPSAMPLE_BINDING_GRID, &target.grid()},
                                     {HEMO_MC_UPSAMPLE_BINDING_SPLAT_GRID, &splatGrid_},
                                     gpu::texelBinding(HEMO_MC_UPSAMPLE_BINDING_SPLAT_FIELD, &splatField_, gpu::texel::kInt),
                                     {HEMO_MC_UPSAMPLE_BINDING_FIELD, &target.field()}});
}

void ParticleField::record(gpu::CommandRecorder& rec, std::uint32_t n, gpu::TimestampQueries* timestamps) const {
  const float h = settings_.h;
  const float kernelNorm = float(21.0 / (16.0 * std::numbers::pi * double(h) * h * h));
  // The field vanishes 2h from the nearest particle: that margin closes the surface.
  const bool coarse = settings_.splatVoxelOverH > 0.0f;
  rec.computeToTransfer();
  rec.fill(coarse ? splatField_ : target_->field(), 0u);
  rec.transferToCompute();
  BoundsPush push{n, settings_.resolution, 2.0f * h, settings_.iso, splat_->workgroupSize(),
                  coarse ? settings_.splatVoxelOverH * h : 0.0f, upsample_->workgroupSize(), 0, {}, {}};
  for (int a = 0; a < 3; ++a) {
    push.clipLo[a] = settings_.clipLo[a];
    push.clipHi[a] = settings_.clipHi[a];
  }
  rec.dispatch(*bounds_, boundsSet_, push, gpu::Groups{1, 1});
  rec.computeToCompute();  // the bounds and the splat's arguments
  rec.dispatchIndirect(*splat_, splatSet_, SplatPush{n, h, kernelNorm, settings_.restDensity}, splatArgs_, 0);
  rec.computeToCompute();
  if (coarse) {
    rec.dispatchIndirect(*upsample_, upsampleSet_, upsampleArgs_, 0);
    rec.computeToCompute();
  }
  if (timestamps) timestamps->mark(rec, "field");
}

}  // namespace hemo::surface
