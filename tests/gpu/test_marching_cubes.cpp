// The GPU surface stages (compute_shaders/mc/) against the CPU double-precision reference
// (hemo/reference/marching_cubes.hpp): the same triangles on random fields, closed meshes,
// the area and volume of a sphere, the particle field and the surface of a block of fluid.
#include "gpu_test.hpp"
#include "hemo/io/output.hpp"
#include "hemo/reference/marching_cubes.hpp"
#include "hemo/surface/marching_cubes.hpp"
#include "interface/mc.h"

#include <glm/geometric.hpp>

#include <cstring>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <numbers>
#include <tuple>

namespace hemo::test {
namespace {

using surface::McVertex;

struct FieldCase {
  glm::dvec3 origin;
  double voxel;
  glm::uvec3 points;
  std::vector<double> values;  // already representable in fixed point
};

reference::ScalarGrid toGrid(const FieldCase& f) {
  reference::ScalarGrid g;
  g.origin = f.origin;
  g.spacing = f.voxel;
  g.points = f.points;
  g.values = f.values;
  return g;
}

FieldCase randomField(std::mt19937_64& rng, glm::uvec3 points, bool closed) {
  FieldCase f{glm::dvec3(-0.01, 0.02, 0.005), 1.0e-3, points, {}};
  std::uniform_real_distribution<double> u(0.0, 1.0);
  f.values.resize(std::size_t(points.x) * points.y * points.z);
  for (std::uint32_t k = 0; k < points.z; ++k) {
    for (std::uint32_t j = 0; j < points.y; ++j) {
      for (std::uint32_t i = 0; i < points.x; ++i) {
        const bool face = i == 0 || j == 0 || k == 0 || i + 1 == points.x || j + 1 == points.y || k + 1 == points.z;
        const double v = closed && face ? 0.0 : u(rng);
        f.values[i + std::size_t(points.x) * (j + std::size_t(points.y) * k)] = surface::fromFixed(surface::toFixed(v));
      }
    }
  }
  return f;
}

class MarchingCubesTest : public GpuTest {
 protected:
  surface::SurfaceMesh extract(surface::MarchingCubes& mc, const FieldCase& f, float iso) {
    mc.uploadField(f.origin, f.voxel, f.points, f.values, iso);
    gpu::CommandRecorder rec(ctx());
    rec.begin();
    mc.record(rec);
    rec.end();
    rec.submitAndWait();
    return mc.readMesh();
  }
};

// Same triangles in the same order (both visit voxels x fastest and a voxel's triangles in
// table order), vertices within 1e-5 voxel, normals within 1e-4.
void expectSameMesh(const surface::SurfaceMesh& gpu, const reference::RefMesh& cpu, double voxel) {
  ASSERT_EQ(gpu.totals.triangles, cpu.triangleCount());
  ASSERT_EQ(gpu.vertices.size(), cpu.positions.size());
  double worstPosition = 0.0, worstNormal = 0.0;
  for (std::size_t v = 0; v < cpu.positions.size(); ++v) {
    worstPosition = std::max(worstPosition, glm::length(glm::dvec3(gpu.vertices[v].position) - cpu.positions[v]));
    worstNormal = std::max(worstNormal, glm::length(glm::dvec3(gpu.vertices[v].normal) - cpu.normals[v]));
    ASSERT_EQ(gpu.vertices[v].position.w, 1.0f);
  }
  EXPECT_LT(worstPosition, 1e-5 * voxel);
  EXPECT_LT(worstNormal, 1e-4);
}

// Welds vertices by their exact bits and checks every edge is shared by exactly two triangles
// in opposite directions, with no degenerate triangle.
void expectWatertight(const std::vector<McVertex>& vertices) {
  std::map<std::tuple<std::uint32_t, std::uint32_t, std::uint32_t>, std::uint32_t> ids;
  const auto id = [&](const glm::vec4& p) {
    std::uint32_t b[3];
    std::memcpy(b, &p, sizeof(b));
    return ids.emplace(std::make_tuple(b[0], b[1], b[2]), std::uint32_t(ids.size())).first->second;
  };
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
  for (std::size_t t = 0; t < vertices.size() / 3; ++t) {
    const glm::vec3 p0(vertices[3 * t].position), p1(vertices[3 * t + 1].position), p2(vertices[3 * t + 2].position);
    ASSERT_GT(glm::length(glm::cross(p1 - p0, p2 - p0)), 0.0f) << "degenerate triangle " << t;
    const std::uint32_t v[3] = {id(vertices[3 * t].position), id(vertices[3 * t + 1].position),
                                id(vertices[3 * t + 2].position)};
    for (int k = 0; k < 3; ++k) ++directed[{v[k], v[(k + 1) % 3]}];
  }
  for (const auto& [edge, count] : directed) {
    ASSERT_EQ(count, 1) << "edge used twice in one direction";
    ASSERT_EQ(directed.count({edge.second, edge.first}), 1u) << "open edge";
  }
}

TEST_F(MarchingCubesTest, RandomFieldsGiveTheReferenceTriangles) {
  auto rng = rngFor();
  const auto table = surface::buildCaseTable();
  surface::MarchingCubes mc(ctx(), 40, 400000);  // random fields: ~3 triangles per voxel
  for (glm::uvec3 points : {glm::uvec3(2, 2, 2), glm::uvec3(9, 7, 6), glm::uvec3(6, 13, 11), glm::uvec3(41, 23, 30)}) {
    SCOPED_TRACE("points " + std::to_string(points.x) + "x" + std::to_string(points.y) + "x" + std::to_string(points.z));
    const FieldCase f = randomField(rng, points, false);
    const auto gpu = extract(mc, f, 0.5f);
    const auto cpu = reference::marchingCubes(toGrid(f), 0.5, table);
    expectSameMesh(gpu, cpu, f.voxel);
    EXPECT_FALSE(gpu.totals.overflow());
    const auto args = mc.args().readback<std::uint32_t>(16);
    EXPECT_EQ(args[8], 3 * gpu.totals.written) << "draw vertex count";
    EXPECT_EQ(args[9], 1u) << "draw instance count";
  }
}

TEST_F(MarchingCubesTest, ClosedFieldsGiveWatertightMeshes) {
  auto rng = rngFor();
  surface::MarchingCubes mc(ctx(), 32, 200000);
  for (int trial = 0; trial < 3; ++trial) {
    const auto mesh = extract(mc, randomField(rng, glm::uvec3(33, 30, 25), true), 0.5f);
    ASSERT_GT(mesh.totals.written, 5000u);
    expectWatertight(mesh.vertices);
  }
}

TEST_F(MarchingCubesTest, SphereAreaAndVolumeOnA128Grid) {
  const double R = 1.0e-3;
  const std::uint32_t n = 129;
  FieldCase f{glm::dvec3(-1.2 * R), 2.4 * R / (n - 1), glm::uvec3(n), {}};
  f.values.resize(std::size_t(n) * n * n);
  for (std::uint32_t k = 0; k < n; ++k) {
    for (std::uint32_t j = 0; j < n; ++j) {
      for (std::uint32_t i = 0; i < n; ++i) {
        const glm::dvec3 x = f.origin + f.voxel * glm::dvec3(i, j, k);
        // Signed distance in units of R (a field of order 1, as the particle field).
        f.values[i + n * (j + std::size_t(n) * k)] = surface::fromFixed(surface::toFixed(1.0 - glm::length(x) / R));
      }
    }
  }
  surface::MarchingCubes mc(ctx(), 128);
  const auto gpu = extract(mc, f, 0.0f);
  reference::RefMesh asRef;
  for (const McVertex& v : gpu.vertices) asRef.positions.emplace_back(v.position);
  const double area = reference::meshArea(asRef), volume = reference::meshVolume(asRef);
  std::printf("GPU sphere at 128^3: %u triangles, area error %.4f%%, volume error %.4f%%\n", gpu.totals.written,
              100 * (area / (4 * std::numbers::pi * R * R) - 1), 100 * (volume / (4.0 / 3 * std::numbers::pi * R * R * R) - 1));
  EXPECT_NEAR(area / (4 * std::numbers::pi * R * R), 1.0, 0.01);
  EXPECT_NEAR(volume / (4.0 / 3 * std::numbers::pi * R * R * R), 1.0, 0.01);
  const auto cpu = reference::marchingCubes(toGrid(f), 0.0, surface::buildCaseTable());
  expectSameMesh(gpu, cpu, f.voxel);
  for (const McVertex& v : gpu.vertices) {
    ASSERT_GT(glm::dot(glm::vec3(v.normal), glm::normalize(glm::vec3(v.position))), 0.99f);
  }
}

TEST_F(MarchingCubesTest, OverflowIsCountedAndClamped) {
  auto rng = rngFor();
  surface::MarchingCubes mc(ctx(), 16, 100);
  const auto mesh = extract(mc, randomField(rng, glm::uvec3(17, 17, 17), false), 0.5f);
  EXPECT_GT(mesh.totals.triangles, 100u);
  EXPECT_EQ(mesh.totals.written, 100u);
  EXPECT_TRUE(mesh.totals.overflow());
  EXPECT_EQ(mesh.vertices.size(), 300u);
  EXPECT_EQ(mc.args().readback<std::uint32_t>(16)[8], 300u);
}

TEST_F(MarchingCubesTest, UploadRejectsGridsBeyondTheCapacity) {
  surface::MarchingCubes mc(ctx(), 8);
  EXPECT_THROW(mc.uploadField(glm::dvec3(0.0), 1.0, glm::uvec3(10, 2, 2), std::vector<double>(40, 0.0), 0.5f),
               std::invalid_argument);
  EXPECT_THROW(mc.uploadField(glm::dvec3(0.0), 1.0, glm::uvec3(3, 3, 3), std::vector<double>(26, 0.0), 0.5f),
               std::invalid_argument);
  EXPECT_THROW(surface::MarchingCubes(ctx(), 0), std::invalid_argument);
}

// A block of fluid particles at rest on a cubic lattice (plus boundary particles the field
// must ignore).
struct Block {
  std::vector<glm::vec4> positions, velocities, state;
  glm::vec3 lo, hi;  // faces of the block (m)
};

Block fluidBlock(float dp, glm::uvec3 cells, float rho0) {
  Block b;
  b.lo = glm::vec3(0.01f, -0.02f, 0.003f);
  b.hi = b.lo + dp * glm::vec3(cells);
  const float mass = rho0 * dp * dp * dp;
  for (std::uint32_t k = 0; k < cells.z; ++k) {
    for (std::uint32_t j = 0; j < cells.y; ++j) {
      for (std::uint32_t i = 0; i < cells.x; ++i) {
        b.positions.emplace_back(b.lo + dp * (glm::vec3(i, j, k) + 0.5f), mass);
        b.velocities.emplace_back(0.0f);
        b.state.emplace_back(rho0 * (1.0f + 0.001f * float((i + j + k) % 5)), 0.0f, 0.0f, 0.0f);
      }
    }
  }
  // Boundary particles below the block and far away: not part of the field or its box.
  for (int i = 0; i < 20; ++i) {
    b.positions.emplace_back(b.lo + glm::vec3(dp * i, 0.0f, -dp), mass);
    b.velocities.emplace_back(0.0f, 0.0f, 0.0f, 1.0f);
    b.state.emplace_back(rho0, 0.0f, 0.0f, 0.0f);
  }
  b.positions.emplace_back(b.lo + glm::vec3(1.0f), mass);
  b.velocities.emplace_back(0.0f, 0.0f, 0.0f, 1.0f);
  b.state.emplace_back(rho0, 0.0f, 0.0f, 0.0f);
  return b;
}

// A block on the GPU: its particles in a store, their densities in a state buffer, an
// extractor, and the field stage over them.
struct BlockField {
  BlockField(gpu::Context& ctx, const Block& b, std::uint32_t maxVoxels, const surface::FieldSettings& settings)
      : n(std::uint32_t(b.positions.size())),
        store(ctx, n),
        state(ctx, std::uint64_t(n) * 16, gpu::MemoryUse::Device, "test state"),
        mc(ctx, maxVoxels),
        field(ctx, mc, store, state, settings) {
    store.upload(b.positions, b.velocities);
    state.upload(b.state);
  }
  // Records the field (and the extraction) and waits.
  void run(gpu::Context& ctx, bool extract = true) {
    gpu::CommandRecorder rec(ctx);
    rec.begin();
    field.record(rec, n);
    if (extract) mc.record(rec);
    rec.end();
    rec.submitAndWait();
  }
  std::uint32_t n;
  sim::ParticleStore store;
  gpu::Buffer state;
  surface::MarchingCubes mc;
  surface::ParticleField field;
};

surface::FieldSettings fieldSettings(std::uint32_t resolution, float h, float rho0) {
  surface::FieldSettings s;
  s.resolution = resolution;
  s.h = h;
  s.restDensity = rho0;
  return s;
}

// The block's fluid particles and densities, for the double-precision field.
struct FluidOfBlock {
  explicit FluidOfBlock(const Block& b) {
    for (std::size_t i = 0; i < b.positions.size(); ++i) {
      if (b.velocities[i].w != 0.0f) continue;
      particles.emplace_back(b.positions[i]);
      densities.push_back(b.state[i].x);
    }
  }
  double at(const glm::dvec3& x, double h) const { return reference::particleField(x, particles, densities, h); }
  std::vector<glm::dvec4> particles;
  std::vector<double> densities;
};

// The largest distance of a mesh vertex from the block's faces (m).
double farthestFromFaces(const std::vector<McVertex>& vertices, const Block& block) {
  double farthest = 0.0;
  for (const McVertex& v : vertices) {
    const glm::vec3 p(v.position);
    const glm::vec3 outside = glm::max(glm::max(block.lo - p, p - block.hi), glm::vec3(0.0f));
    const glm::vec3 inside = glm::min(p - block.lo, block.hi - p);
    const float d = glm::length(outside) > 0.0f ? glm::length(outside) : std::min({inside.x, inside.y, inside.z});
    farthest = std::max(farthest, double(d));
  }
  return farthest;
}

TEST_F(MarchingCubesTest, ParticleFieldMatchesTheReferenceAndWrapsTheBlock) {
  const float dp = 1.0e-3f, h = 1.3f * dp, rho0 = 1000.0f;
  const Block block = fluidBlock(dp, glm::uvec3(12, 8, 6), rho0);
  BlockField gpuBlock(ctx(), block, 64, fieldSettings(48, h, rho0));
  const auto run = [&] {
    gpuBlock.run(ctx());
    return std::make_pair(gpuBlock.mc.readField(), gpuBlock.mc.readMesh());
  };
  const auto [values, mesh] = run();

  // The grid: the fluid's box grown by 2h, 48 voxels along its longest side.
  const surface::McGrid g = mesh.grid;
  const glm::vec3 grown = (block.hi - block.lo) - dp + 4.0f * h;
  EXPECT_NEAR(g.origin[3], std::max({grown.x, grown.y, grown.z}) / 48.0f, 1e-9f);
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(g.origin[a], block.lo[a] + 0.5f * dp - 2.0f * h, 1e-7f);
  EXPECT_EQ(g.points[0], 49u);

  // Field against the double-precision sum at every point.
  const FluidOfBlock fluid(block);
  double worst = 0.0;
  reference::ScalarGrid ref;
  ref.origin = glm::dvec3(g.origin[0], g.origin[1], g.origin[2]);
  ref.spacing = g.origin[3];
  ref.points = glm::uvec3(g.points[0], g.points[1], g.points[2]);
  ref.values.resize(values.size());
  for (std::uint32_t k = 0; k < ref.points.z; ++k) {
    for (std::uint32_t j = 0; j < ref.points.y; ++j) {
      for (std::uint32_t i = 0; i < ref.points.x; ++i) {
        const glm::dvec3 x = ref.origin + ref.spacing * glm::dvec3(i, j, k);
        const double expected = fluid.at(x, h);
        const std::size_t idx = ref.index(i, j, k);
        worst = std::max(worst, std::abs(surface::fromFixed(values[idx]) - expected));
        ref.values[idx] = surface::fromFixed(values[idx]);
      }
    }
  }
  EXPECT_LT(worst, 5e-5) << "field against the double-precision sum";

  // The surface: closed, and within one particle spacing of the block's faces.
  ASSERT_GT(mesh.totals.written, 1000u);
  expectWatertight(mesh.vertices);
  const double farthest = farthestFromFaces(mesh.vertices, block);
  std::printf("block surface: %u triangles, farthest vertex %.3f dp from the block's faces\n", mesh.totals.written,
              farthest / dp);
  EXPECT_LT(farthest, dp);
  // The extraction of that field equals the reference's.
  expectSameMesh(mesh, reference::marchingCubes(ref, 0.5, surface::buildCaseTable()), ref.spacing);

  // PLY export: welded vertices (a closed surface: V - E + F = 2 per component, here one
  // block), the header's counts and the binary body's size.
  const io::IndexedMesh welded = io::weld(mesh.vertices);
  ASSERT_EQ(welded.indices.size(), mesh.vertices.size());
  const std::size_t faces = welded.indices.size() / 3;
  EXPECT_EQ(std::int64_t(welded.positions.size()) - std::int64_t(3 * faces / 2) + std::int64_t(faces), 2);
  const auto path = std::filesystem::temp_directory_path() / "hemo_test_block.ply";
  io::writeSurfacePly(path, mesh, 0.25);
  std::ifstream in(path, std::ios::binary);
  std::string header, line;
  while (std::getline(in, line) && line != "end_header") header += line + "\n";
  EXPECT_NE(header.find("element vertex " + std::to_string(welded.positions.size()) + "\n"), std::string::npos);
  EXPECT_NE(header.find("element face " + std::to_string(faces) + "\n"), std::string::npos);
  EXPECT_NE(header.find("comment time_s 0.25\n"), std::string::npos);
  const auto bodyStart = std::uint64_t(in.tellg());
  EXPECT_EQ(std::filesystem::file_size(path) - bodyStart, welded.positions.size() * 24 + faces * 13);
  std::filesystem::remove(path);

  // Bit-identical when run again.
  const auto [values2, mesh2] = run();
  EXPECT_EQ(values, values2);
  ASSERT_EQ(mesh.vertices.size(), mesh2.vertices.size());
  EXPECT_EQ(0, std::memcmp(mesh.vertices.data(), mesh2.vertices.data(), mesh.vertices.size() * sizeof(McVertex)));
}

// A grid much finer than the kernel: each particle's support covers ~64^3 points, more loop
// iterations than llvmpipe lets one shader invocation run (65,535), so the splat must split a
// particle's work (mc/bounds.comp).
// A device that allows only a few workgroups along x (forced low): every dispatch, those whose
// counts the host computes and those whose counts the GPU writes (the splat, the upsample,
// classify and generate), folds into y, and the field and the surface come out bit-identical.
TEST_F(MarchingCubesTest, FoldedDispatchesGiveTheSameSurface) {
  const float dp = 1.0e-3f, h = 1.3f * dp, rho0 = 1000.0f;
  const Block block = fluidBlock(dp, glm::uvec3(12, 8, 6), rho0);
  surface::FieldSettings settings = fieldSettings(48, h, rho0);
  BlockField wide(ctx(), block, 64, settings);
  wide.run(ctx());
  gpu::ContextOptions options;
  options.validation = true;
  options.limits.maxComputeWorkGroupCountX = 5;
  gpu::Context narrow(options);
  ASSERT_EQ(narrow.limits().maxComputeWorkGroupCount[0], 5u);
  BlockField folded(narrow, block, 64, settings);
  folded.run(narrow);
  const auto a = wide.mc.readMesh(), b = folded.mc.readMesh();
  EXPECT_EQ(wide.mc.readField(), folded.mc.readField());
  ASSERT_EQ(a.totals.written, b.totals.written);
  ASSERT_GT(a.totals.written, 1000u);
  EXPECT_EQ(0, std::memcmp(a.vertices.data(), b.vertices.data(), a.vertices.size() * sizeof(a.vertices[0])));
  // The counts the GPU wrote for classify and generate fold at the context's limit.
  const auto args = folded.mc.args().readback<std::uint32_t>(16);
  for (const std::uint32_t at : {std::uint32_t(HEMO_MC_ARGS_CLASSIFY), std::uint32_t(HEMO_MC_ARGS_GENERATE)}) {
    EXPECT_LE(args[at], 5u) << "arguments at " << at;
    EXPECT_GT(args[at + 1], 1u) << "arguments at " << at;
  }
  for (const auto& m : narrow.takeValidationMessages()) ADD_FAILURE() << m;
}

TEST_F(MarchingCubesTest, ParticleFieldOnAGridFarFinerThanTheKernel) {
  const float dp = 1.0e-3f, h = 1.3f * dp, rho0 = 1000.0f;
  const Block block = fluidBlock(dp, glm::uvec3(4, 4, 3), rho0);
  BlockField gpuBlock(ctx(), block, 100, fieldSettings(100, h, rho0));
  gpuBlock.run(ctx(), false);
  const surface::McGrid g = gpuBlock.mc.readGrid();
  ASSERT_GT(2.0f * h / g.origin[3], 30.0f) << "support radius in voxels";
  const auto values = gpuBlock.mc.readField();
  const FluidOfBlock fluid(block);
  double worst = 0.0, largest = 0.0;
  for (std::uint32_t k = 0; k < g.points[2]; k += 3) {
    for (std::uint32_t j = 0; j < g.points[1]; j += 3) {
      for (std::uint32_t i = 0; i < g.points[0]; i += 3) {
        const glm::dvec3 x = glm::dvec3(g.origin[0], g.origin[1], g.origin[2]) + double(g.origin[3]) * glm::dvec3(i, j, k);
        const double got = surface::fromFixed(values[i + std::size_t(g.points[0]) * (j + std::size_t(g.points[1]) * k)]);
        worst = std::max(worst, std::abs(got - fluid.at(x, h)));
        largest = std::max(largest, got);
      }
    }
  }
  EXPECT_LT(worst, 5e-5);
  EXPECT_GT(largest, 0.5);
}

// The splat on a grid of h/2, interpolated onto a much finer extraction grid: the extraction
// grid equals the trilinear interpolation of the double-precision field at the splat grid's
// points, stays within 0.07 of the direct sum (trilinear interpolation of the kernel's
// curvature at h/2: measured 0.061, at the block's edges, where the field falls fastest), and
// still wraps the block within a spacing.
TEST_F(MarchingCubesTest, CoarseSplatGridIsInterpolatedOntoTheExtractionGrid) {
  const float dp = 1.0e-3f, h = 1.3f * dp, rho0 = 1000.0f;
  const Block block = fluidBlock(dp, glm::uvec3(10, 7, 6), rho0);
  surface::FieldSettings settings = fieldSettings(96, h, rho0);
  settings.splatVoxelOverH = 0.5f;
  BlockField gpuBlock(ctx(), block, 96, settings);
  gpuBlock.run(ctx());
  const surface::MarchingCubes& mc = gpuBlock.mc;
  const surface::McGrid g = mc.readGrid();
  const surface::McGrid sg = gpuBlock.field.readSplatGrid();
  ASSERT_NEAR(sg.origin[3], 0.5f * h, 1e-9f);
  ASSERT_GT(sg.origin[3], 2.5f * g.origin[3]) << "the splat grid is coarser";
  for (int a = 0; a < 3; ++a) {
    ASSERT_EQ(sg.origin[a], g.origin[a]);
    ASSERT_GE(double(sg.points[a] - 1) * sg.origin[3], double(g.points[a] - 1) * g.origin[3]);
  }
  const FluidOfBlock fluid(block);
  const glm::dvec3 origin(g.origin[0], g.origin[1], g.origin[2]);
  const auto coarseAt = [&](glm::uvec3 c) { return fluid.at(origin + double(sg.origin[3]) * glm::dvec3(c), h); };
  const auto values = mc.readField();
  double worstTwin = 0.0, worstDirect = 0.0;
  for (std::uint32_t k = 0; k < g.points[2]; k += 2) {
    for (std::uint32_t j = 0; j < g.points[1]; j += 2) {
      for (std::uint32_t i = 0; i < g.points[0]; i += 2) {
        const glm::dvec3 u = glm::dvec3(i, j, k) * (double(g.origin[3]) / double(sg.origin[3]));
        const glm::uvec3 c = glm::min(glm::uvec3(glm::floor(u)), glm::uvec3(sg.points[0] - 2, sg.points[1] - 2, sg.points[2] - 2));
        const glm::dvec3 t = glm::clamp(u - glm::dvec3(c), 0.0, 1.0);
        double v = 0.0;
        for (int corner = 0; corner < 8; ++corner) {
          const glm::uvec3 o(corner & 1, (corner >> 1) & 1, corner >> 2);
          const double w = (o.x ? t.x : 1 - t.x) * (o.y ? t.y : 1 - t.y) * (o.z ? t.z : 1 - t.z);
          v += w * coarseAt(c + o);
        }
        const double got = surface::fromFixed(values[i + std::size_t(g.points[0]) * (j + std::size_t(g.points[1]) * k)]);
        worstTwin = std::max(worstTwin, std::abs(got - v));
        const glm::dvec3 x = origin + double(g.origin[3]) * glm::dvec3(i, j, k);
        worstDirect = std::max(worstDirect, std::abs(got - fluid.at(x, h)));
      }
    }
  }
  std::printf("coarse splat: %.2e from its double twin, %.4f from the direct sum\n", worstTwin, worstDirect);
  EXPECT_LT(worstTwin, 5e-5);
  EXPECT_LT(worstDirect, 0.07);
  const surface::SurfaceMesh mesh = mc.readMesh();
  ASSERT_GT(mesh.totals.written, 1000u);
  expectWatertight(mesh.vertices);
  const double farthest = farthestFromFaces(mesh.vertices, block);
  std::printf("coarse splat: block surface within %.3f dp of its faces\n", farthest / dp);
  EXPECT_LT(farthest, dp);
}

// A droplet that flew far away would stretch the grid over metres; the clip box keeps the
// grid (and its voxel) on the region of interest.
TEST_F(MarchingCubesTest, TheGridStaysInsideTheClipBox) {
  const float dp = 1.0e-3f, h = 1.3f * dp;
  Block block = fluidBlock(dp, glm::uvec3(6, 6, 6), 1000.0f);
  block.positions.emplace_back(block.lo + glm::vec3(1.0f, 0.0f, 0.0f), block.positions[0].w);  // 1 m away
  block.velocities.emplace_back(0.0f);
  block.state.emplace_back(1000.0f, 0.0f, 0.0f, 0.0f);
  surface::FieldSettings settings = fieldSettings(32, h, 1000.0f);
  settings.clipLo = block.lo - glm::vec3(4.0f * dp);
  settings.clipHi = block.hi + glm::vec3(4.0f * dp);
  BlockField gpuBlock(ctx(), block, 32, settings);
  gpuBlock.run(ctx());
  const surface::SurfaceMesh mesh = gpuBlock.mc.readMesh();
  const surface::McGrid& g = mesh.grid;
  for (int a = 0; a < 3; ++a) {
    EXPECT_GE(g.origin[a], settings.clipLo[a] - 1e-7f);
    EXPECT_LE(g.origin[a] + g.origin[3] * float(g.points[a] - 1), settings.clipHi[a] + g.origin[3]);
  }
  EXPECT_LT(g.origin[3], 14.0f * dp / 32.0f + 1e-7f) << "voxel set by the clipped box";
  ASSERT_GT(mesh.totals.written, 100u);
  for (const McVertex& v : mesh.vertices) ASSERT_LT(v.position.x, block.hi.x + 2.0f * h);
  EXPECT_THROW(surface::ParticleField(ctx(), gpuBlock.mc, gpuBlock.store, gpuBlock.state,
                                      [&] {
                                        surface::FieldSettings bad = settings;
                                        bad.clipHi.y = bad.clipLo.y;
                                        return bad;
                                      }()),
               std::invalid_argument);
}

TEST_F(MarchingCubesTest, NoFluidGivesNoSurface) {
  const float dp = 1.0e-3f;
  Block block = fluidBlock(dp, glm::uvec3(2, 2, 2), 1000.0f);
  for (auto& v : block.velocities) v.w = 1.0f;  // everything boundary
  BlockField gpuBlock(ctx(), block, 16, fieldSettings(16, 1.3f * dp, 1000.0f));
  gpuBlock.run(ctx());
  const auto totals = gpuBlock.mc.readTotals();
  EXPECT_EQ(totals.triangles, 0u);
  EXPECT_EQ(totals.runs, 0u);
  EXPECT_EQ(gpuBlock.mc.args().readback<std::uint32_t>(16)[8], 0u);
}

}  // namespace
}  // namespace hemo::test
