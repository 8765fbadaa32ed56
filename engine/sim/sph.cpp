#include "hemo/sim/sph.hpp"

#include "hemo/gpu/pipeline_cache.hpp"
#include "hemo/reference/sph.hpp"
#include "interface/scan.h"
#include "interface/sph.h"
#include "interface/tool.h"
#include "interface/grid.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <numbers>
#include <stdexcept>
#include <string>

namespace hemo::sim {

namespace {
constexpr std::uint32_t kWorkgroup = 256;

struct CountPush {
  std::uint32_t n;
};
struct DensityPush {  // sph/density.comp: the slots [first, n), in one page of the list
  std::uint32_t n, clockIn, first;
};
struct SpsPush {  // sph/sps_stress.comp: the slots [first, n), in one page of the list
  std::uint32_t n, first;
};
struct BuildPush {  // sph/build_list.comp
  NeighbourGrid::Push grid;
  std::uint32_t first, end;  // the slots [first, end) get lists, in one page
};
struct ClusterBuildPush {  // sph/build_clusters.comp
  NeighbourGrid::Push grid;
  std::uint32_t first, end;  // the slots [first, end)
  std::uint32_t capacity;
  std::uint32_t base;      // the cluster of slot `first`
  std::uint32_t boundary;  // 1: boundary members
};
struct ClusterOrderPush {  // sph/cluster_order.comp
  std::uint32_t count, list, base;
};
struct ClusterPush {  // the cluster pair passes
  std::uint32_t fluid, capacity;
  std::uint32_t third;  // density: the clock record it reads; forces: n (slots past the fluid's to set)
};
struct BoundaryPush {  // sph/boundary_pressure.comp
  std::uint32_t first, n, clockIn;  // the range modes: the slots [first, n)
  std::uint32_t mode;               // HEMO_BPRESSURE_*
};
struct BoundaryClusterPush {  // sph/boundary_clusters.comp
  BoundaryPush range;
  std::uint32_t capacity, base;  // entries per cluster; the cluster of slot range.first
};
struct ForcesPush {  // sph/forces.comp: the slots [first, n), in one page of the list
  std::uint32_t n, first;
  std::uint32_t last;  // 1: the pass's last dispatch (it writes the time-step partials' count)
};
struct DfsphPredictPush {  // sph/dfsph_predict.comp: the slots [0, n)
  std::uint32_t n, clockIn;
  float endTime;
  std::uint32_t iteration;  // 0: the solve's first prediction
  std::uint32_t mode;       // HEMO_DFSPH_MODE_*
};
struct DfsphCorrectPush {  // sph/dfsph_correct.comp
  std::uint32_t n, mode;
};
struct DfsphReducePush {  // sph/dfsph_reduce.comp
  std::uint32_t partialCount, fluid, iteration, maxIterations;
  float tolerance;
  std::uint32_t slots, statBase, recorded, minIterations;
};
struct DtReducePush {  // sph/dt_reduce.comp
  std::uint32_t wallBase;  // the wall stage's first partial
  std::uint32_t passes;    // bit 0: the force pass ran, bit 1: the wall stage ran, bit 2: the tools' contact
  std::uint32_t tools, toolStride, clockIn, logIndex;  // the tools' force sums (tools 0: none)
};
struct IntegratePush {
  std::uint32_t n, step, logIndex;
  float endTime;
  std::uint32_t clockIn;
  float threshold;  // the rebuild test (full stages): whether to collect the tile boxes, m
  std::uint32_t wallAdvanced;  // 1: the wall's substeps have moved the wall particles
};
static_assert(sizeof(IntegratePush) == 28);
struct DecidePush {  // sph/rebuild_decide.comp
  float threshold;            // half the skin, m
  std::uint32_t gateSlots;    // the rebuild gate's slots
  std::uint32_t staticSlots;  // 1: slots the integrator left out hold rigid boundary particles (displacement 0)
  std::uint32_t groupsX, groupsY;  // the integrator's workgroups, for the next step's indirect arguments
};
// Scalars only, so the GLSL block has the same offsets (a uvec2 there would align to 8 and
// read past this struct, and the GPU hang).
static_assert(sizeof(DecidePush) == 20);
static_assert(SphSolver::kListBoundaryBit == HEMO_LIST_BOUNDARY_BIT);
static_assert(HEMO_GRID_FLUID_KIND == HEMO_KIND_FLUID);  // the grid sorts the fluid first

std::uint64_t perParticle(const ParticleStore& particles, std::uint64_t bytes) {
  return std::uint64_t(std::max(particles.capacity(), 1u)) * bytes;
}

// Clusters (interface/sph.h): as many as the slots could need (the fluid's and the boundary
// particles', each part's last cluster perhaps not full), and the entries of each: every
// member's neighbours and itself even when each member walks alone (all in different rows of
// cells), plus the padding of the two sections' last texels (the build stores whole texels of
// four, so the sections must not share one: up to three entries each).
std::uint64_t clustersFor(const ParticleStore& particles) {
  return std::uint64_t(std::max(particles.capacity(), 1u)) / HEMO_CLUSTER_SIZE + 2;
}
std::uint32_t clusterEntries(std::uint32_t neighbourCapacity) {
  return (HEMO_CLUSTER_SIZE * (neighbourCapacity + 1) + 6 + 3) & ~3u;
}
// The list's layout (interface/sph.h): on a CPU device each SIMD lane walks its own list,
// and entries next to each other stream from cache; interleaved entries, which coalesce
// on a GPU, cost a cache miss per entry there (pair_gather in hemo-bench primitives).
bool contiguousList(const gpu::Context& context, const SphSettings& s) {
  const bool cpu = context.info().type == VK_PHYSICAL_DEVICE_TYPE_CPU;
  return s.listLayout == ListLayout::Contiguous || s.listLayout == ListLayout::Clusters ||
         (s.listLayout == ListLayout::Auto && cpu);
}
// Contiguous lists whose capacity is a multiple of 4 are read four entries per texel
// (common/sph_params.glsl, hemo_list_texel).
std::uint32_t listReadWidthFor(const gpu::Context& context, const SphSettings& s) {
  if (s.neighbourSearch == NeighbourSearch::Cells) return 1u;
  return contiguousList(context, s) && s.neighbourCapacity % 4u == 0u ? 4u : 1u;
}

// Slots per page of the neighbour list and the interacting pairs (interface/sph.h, "pages"):
// all the slots when one buffer holds their lists within every binding limit of the device
// (a storage buffer's range, the texels of a texel buffer as the pair passes read it, the
// largest allocation), else the largest power of two of slots whose lists do. A page of
// fewer than 1024 slots (a device with absurdly small limits) is refused.
std::uint32_t listPageSlotsFor(const gpu::Context& context, const SphSettings& s, std::uint32_t slots) {
  const std::uint64_t entryBytes = 4;
  const std::uint64_t slotBytes = std::uint64_t(s.neighbourCapacity) * entryBytes;
  std::uint64_t limit = context.limits().maxStorageBufferRange;
  limit = std::min<std::uint64_t>(limit, std::uint64_t(context.limits().maxTexelBufferElements) * entryBytes *
                                             listReadWidthFor(context, s));
  if (context.maxAllocationSize() != 0) limit = std::min<std::uint64_t>(limit, context.maxAllocationSize());
  slots = std::max(slots, 1u);
  if (std::uint64_t(slots) * slotBytes <= limit) return slots;
  std::uint64_t page = 1;
  while (page * 2 * slotBytes <= limit) page *= 2;
  if (page < 1024) {
    throw gpu::GpuError("the neighbour list of " + std::to_string(slots) + " particles (" + std::to_string(s.neighbourCapacity) +
                        " entries each) would need pages of " + std::to_string(page) +
                        " particles to stay within the device's buffer limits (" + std::to_string(limit) +
                        " bytes per binding); hemo needs at least 1024 per page");
  }
  return static_cast<std::uint32_t>(page);
}
std::uint32_t listPagesFor(const gpu::Context& context, const SphSettings& s, const ParticleStore& particles) {
  if (s.neighbourSearch == NeighbourSearch::Cells) return 1;  // (no list: one placeholder page)
  const std::uint32_t slots = std::max(particles.capacity(), 1u);
  const std::uint32_t pageSlots = listPageSlotsFor(context, s, slots);
  return (slots + pageSlots - 1) / pageSlots;
}
// Entries of page p of the list (and of the interacting pairs), pages of pageSlots slots: its
// slots' lists, or with the interleaved layout up to its last slot's last entry (stride
// pageSlots).
std::uint64_t listPageEntries(const gpu::Context& context, const SphSettings& s, std::uint32_t slots,
                              std::uint32_t pageSlots, std::uint32_t p) {
  const std::uint64_t count = std::min<std::uint64_t>(pageSlots, slots - std::uint64_t(p) * pageSlots);
  const std::uint64_t cap = s.neighbourCapacity;
  return contiguousList(context, s) ? count * cap : (cap - 1) * pageSlots + count;
}
// Bytes of the list and the interacting pairs for `slots` slots.
std::uint64_t listBytesFor(const gpu::Context& context, const SphSettings& s, std::uint32_t slots) {
  const std::uint32_t pageSlots = listPageSlotsFor(context, s, slots);
  const std::uint32_t pages = (slots + pageSlots - 1) / pageSlots;
  std::uint64_t bytes = 0;
  for (std::uint32_t p = 0; p < pages; ++p) bytes += 2 * 4 * listPageEntries(context, s, slots, pageSlots, p);
  return bytes;
}
// An upper bound of what the grid and the solver hold per slot besides the lists (their
// per-particle buffers, RK2's and SPS's included).
constexpr std::uint64_t kSolverBytesPerSlot = 256;
// The settings with NeighbourSearch::Auto resolved: the list where the device's memory holds
// it with the solver's other buffers (and its pages would not be absurdly small), else cells.
SphSettings resolveNeighbourSearch(const gpu::Context& context, const ParticleStore& particles, SphSettings s) {
  if (s.neighbourSearch != NeighbourSearch::Auto) return s;
  if (s.pressureSolver == PressureSolver::Dfsph || s.parkedSlots) {  // (the solve's passes read the list)
    s.neighbourSearch = NeighbourSearch::List;
    return s;
  }
  const std::uint32_t slots = std::max(particles.capacity(), 1u);
  s.neighbourSearch = NeighbourSearch::List;
  try {
    const std::uint64_t needed = context.deviceMemoryBytes() + std::uint64_t(slots) * kSolverBytesPerSlot +
                                 listBytesFor(context, s, slots);
    if (needed > context.deviceMemoryCapacity()) s.neighbourSearch = NeighbourSearch::Cells;
  } catch (const gpu::GpuError&) {
    s.neighbourSearch = NeighbourSearch::Cells;
  }
  return s;
}
// The open ends' profile bins (interface/sph.h).
constexpr std::uint64_t kOpenSumWords = HEMO_OPEN_SUM_WORDS, kOpenProfile = HEMO_OPEN_PROFILE_SIZE;
static_assert(OpenEnds::kMaxEnds == HEMO_OPEN_MAX_ENDS);
// The boundary pass's indirect arguments of each page of the list, apart by the largest
// storage-buffer offset alignment Vulkan allows.
constexpr std::uint64_t kActiveArgsStride = 256;
std::uint64_t activeArgsBytes(const gpu::Context& context, const SphSettings& s, const ParticleStore& particles) {
  const std::uint32_t pages = listPagesFor(context, s, particles);
  return pages > 1 ? kActiveArgsStride * pages : 16;
}
// Slots of the rebuild gate, two regions (every slot sorted, or the moving ones): each records
// the grid's four passes, the list's build once per page, up to three cluster passes and the
// boundary sort once per page (SphSolver::recordNeighbours).
std::uint32_t rebuildGateSlots(const gpu::Context& context, const SphSettings& s, const ParticleStore& particles) {
  const std::uint32_t pages = listPagesFor(context, s, particles);
  // (+ 8: open ends' refill, three passes and the scan's levels)
  return 2 * std::max(32u, 16u + 2u * pages);
}

// Whether the fluid walks clusters (ListLayout): on CPU devices, where a fetch costs per lane,
// for summation density with Newtonian blood and without the SPS term (the cluster passes have none of them), with the list
// in one page.
bool clusterLayout(const gpu::Context& context, const SphSettings& s, const ParticleStore& particles) {
  const bool cpu = context.info().type == VK_PHYSICAL_DEVICE_TYPE_CPU;
  const bool clusterable = s.neighbourSearch != NeighbourSearch::Cells && !s.sps && !s.nonNewtonian() &&
                           s.densityMethod == DensityMethod::Summation &&
                           s.pressureSolver == PressureSolver::Wcsph && !s.parkedSlots &&
                           particles.capacity() <= HEMO_CLUSTER_MAX_SLOTS && listPagesFor(context, s, particles) == 1;
  return clusterable && (s.listLayout == ListLayout::Clusters || (s.listLayout == ListLayout::Auto && cpu));
}

// The partials one pass over all slots may write when each SIMD group writes one (the time
// step's, common/dt_fold.glsl; the rebuild test's, sph/integrate.comp): at most one per
// invocation of its workgroups (a device may run SIMD groups of one).
std::uint64_t partialsPerPass(const ParticleStore& particles) {
  return (std::uint64_t(std::max(particles.capacity(), 1u)) + kWorkgroup - 1) / kWorkgroup * kWorkgroup;
}

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument(what);
}
bool finitePositive(float x) { return std::isfinite(x) && x > 0.0f; }
}  // namespace

void SphSettings::validate() const {
  require(finitePositive(spacing), "particle spacing must be a positive length in m");
  require(std::isfinite(smoothingRatio) && smoothingRatio >= 0.5f && smoothingRatio <= 3.0f,
          "smoothing ratio h/dp must be between 0.5 and 3");
  require(finitePositive(restDensity), "rest density must be positive (kg/m^3)");
  require(std::isfinite(viscosity) && viscosity >= 0.0f, "viscosity must be >= 0 (Pa s)");
  if (rheology == Rheology::CarreauYasuda) {
    const CarreauYasuda& cy = carreau;
    require(finitePositive(cy.mu0), "Carreau-Yasuda zero-shear viscosity must be positive (Pa s)");
    require(std::isfinite(cy.muInf) && cy.muInf >= 0.0f && cy.muInf <= cy.mu0,
            "Carreau-Yasuda infinite-shear viscosity must be in [0, zero-shear viscosity] (Pa s)");
    require(finitePositive(cy.lambda), "Carreau-Yasuda relaxation time must be positive (s)");
    require(finitePositive(cy.n) && cy.n <= 1.0f, "Carreau-Yasuda power-law index must be in (0, 1] (shear-thinning blood)");
    require(finitePositive(cy.a) && cy.a <= 10.0f, "Carreau-Yasuda exponent a must be in (0, 10]");
  }
  require(finitePositive(soundSpeed), "speed of sound must be positive (m/s)");
  for (int a = 0; a < 3; ++a) {
    require(std::isfinite(gravity[a]) && std::isfinite(bodyForce[a]), "gravity and body force must be finite");
  }
  require(std::isfinite(repulsionScale) && repulsionScale >= 0.0f, "repulsion scale must be >= 0");
  require(std::isfinite(repulsionCutoffRatio) && repulsionCutoffRatio > 0.0f && repulsionCutoffRatio <= 2.0f * smoothingRatio,
          "repulsion cutoff D must be positive and at most the kernel support");
  require(finitePositive(cflAcoustic) && cflAcoustic <= 1.0f, "acoustic CFL number must be in (0, 1]");
  require(finitePositive(cflForce) && cflForce <= 1.0f, "force CFL number must be in (0, 1]");
  require(finitePositive(maxTimeStep), "maximum time step must be positive (s)");
  require(neighbourCapacity >= 8 && neighbourCapacity <= 1024, "neighbour capacity must be in [8, 1024]");
  require(std::isfinite(listSkin) && listSkin >= 0.0f && listSkin <= 1.0f, "neighbour-list skin must be in [0, 1]");
  require(std::isfinite(dampingRate) && dampingRate >= 0.0f, "settling damping rate must be >= 0 (1/s)");
  require(std::isfinite(dampingUntil) && dampingUntil >= 0.0f, "settling time must be >= 0 (s)");
  require(std::isfinite(smagorinsky) && smagorinsky >= 0.0f && smagorinsky <= 1.0f, "Smagorinsky constant must be in [0, 1]");
  require(std::isfinite(blinn) && blinn >= 0.0f && blinn <= 1.0f, "Blinn constant must be in [0, 1]");
  require(std::isfinite(backgroundPressure), "background pressure must be finite (Pa)");
  require(std::isfinite(backgroundPressureRamp) && backgroundPressureRamp >= 0.0f,
          "background pressure ramp must be >= 0 (s)");
  require(std::isfinite(deltaSph) && deltaSph >= 0.0f && deltaSph <= 1.0f, "delta-SPH coefficient must be in [0, 1]");
  require(std::isfinite(solverTolerance) && solverTolerance > 0.0f && solverTolerance <= 0.1f,
          "pressure solver tolerance must be in (0, 0.1] (mean compression / rest density)");
  require(solverMaxIterations >= 1 && solverMaxIterations <= 1000, "pressure solver iterations must be in [1, 1000]");
  if (pressureSolver == PressureSolver::Dfsph) {
    require(densityMethod == DensityMethod::Summation, "the DFSPH pressure solver needs summation density");
    require(integrator == Integrator::SymplecticEuler, "the DFSPH pressure solver steps with symplectic Euler");
    require(neighbourSearch != NeighbourSearch::Cells, "the DFSPH pressure solver needs the neighbour list");
    require(listLayout != ListLayout::Clusters, "the DFSPH pressure solver does not walk clusters");
  }
  if (parkedSlots) {
    require(pressureSolver == PressureSolver::Wcsph, "open vessel ends need the WCSPH pressure solver");
    require(neighbourSearch != NeighbourSearch::Cells, "open vessel ends need the neighbour list");
    require(listLayout != ListLayout::Clusters, "open vessel ends do not walk clusters");
  }
}

double CarreauYasuda::at(double shearRate) const {
  return double(muInf) + (double(mu0) - muInf) * std::pow(1.0 + std::pow(double(lambda) * shearRate, double(a)), (double(n) - 1.0) / a);
}

double SphSettings::maxViscosity() const { return rheology == Rheology::CarreauYasuda ? std::max(carreau.mu0, carreau.muInf) : viscosity; }

float SphSettings::particleMass() const {
  const double dp = spacing, hh = h();
  const int reach = int(std::ceil(2.0 * hh / dp)) + 1;
  double sum = 0.0;
  for (int a = -reach; a <= reach; ++a)
    for (int b = -reach; b <= reach; ++b)
      for (int c = -reach; c <= reach; ++c) {
        sum += reference::kernelW(dp * std::sqrt(double(a * a + b * b + c * c)), hh);
      }
  return float(restDensity / sum);
}

double SphSettings::viscousLatticeFactor() const {
  // The Morris term's estimate of d^2 v / dz^2 for v = z^2 (exactly 2) on the initial cubic
  // lattice, with particle volumes 1 / sum_j W (as the calibrated mass gives), over 2.
  const double dp = spacing, hh = h(), etaSq = 0.01 * hh * hh;
  const int reach = int(std::ceil(2.0 * hh / dp)) + 1;
  double sumW = 0.0, sum = 0.0;
  for (int a = -reach; a <= reach; ++a)
    for (int b = -reach; b <= reach; ++b)
      for (int c = -reach; c <= reach; ++c) {
        const double r = dp * std::sqrt(double(a * a + b * b + c * c));
        sumW += reference::kernelW(r, hh);
        if (r > 0.0) sum -= 2.0 * r * reference::kernelDwdr(r, hh) / (r * r + etaSq) * (dp * c) * (dp * c);
      }
  return sum / sumW / 2.0;
}

double SphSettings::stiffnessDenominatorAtRest() const {
  // sum_j |m gradW_ij|^2 over the cubic lattice's neighbours (sum_j m gradW_ij cancels there)
  const double dp = spacing, hh = h(), m = particleMass();
  const int reach = int(std::ceil(2.0 * hh / dp)) + 1;
  double sum = 0.0;
  for (int a = -reach; a <= reach; ++a)
    for (int b = -reach; b <= reach; ++b)
      for (int c = -reach; c <= reach; ++c) {
        const double g = m * reference::kernelDwdr(dp * std::sqrt(double(a * a + b * b + c * c)), hh);
        sum += g * g;
      }
  return sum;
}

SphParams makeParams(const SphSettings& s) {
  s.validate();
  SphParams p{};
  const glm::vec3 g = s.gravity + s.bodyForce;
  p.gravity[0] = g.x;
  p.gravity[1] = g.y;
  p.gravity[2] = g.z;
  p.gravity[3] = 0.0f;
  const double h = s.h();
  p.h = float(h);
  p.supportRadius = s.supportRadius();
  p.listRadius = s.listRadius();
  p.kernelNorm = float(21.0 / (16.0 * std::numbers::pi * h * h * h));
  p.rho0 = s.restDensity;
  p.taitB = float(double(s.soundSpeed) * s.soundSpeed * s.restDensity / 7.0);
  p.mu = float(s.viscosity / s.viscousLatticeFactor());
  p.etaSq = float(0.01 * h * h);
  p.psi = float(s.repulsionScale * double(s.soundSpeed) * s.soundSpeed / (2.0 * h));
  p.repulsionCutoff = s.repulsionCutoffRatio * s.spacing;
  p.wallSpacing = s.spacing;
  p.cflAcoustic = s.cflAcoustic;
  p.cflForce = s.cflForce;
  p.dtViscous = s.maxViscosity() > 0.0 ? float(0.125 * h * h * s.restDensity / s.maxViscosity()) : 3.0e38f;
  if (s.rheology == Rheology::CarreauYasuda) {
    const double lattice = s.viscousLatticeFactor();
    p.carreau[0] = float(s.carreau.muInf / lattice);
    p.carreau[1] = float((double(s.carreau.mu0) - s.carreau.muInf) / lattice);
    p.carreau[2] = s.carreau.lambda;
    p.carreau[3] = s.carreau.a;
    p.rheologyExponent = float((double(s.carreau.n) - 1.0) / s.carreau.a);
    p.mu = float(s.carreau.mu0 / lattice);  // (unused by the passes, which read each particle's)
  }
  p.dtMax = s.maxTimeStep;
  p.c0 = s.soundSpeed;
  p.clampNegativePressure = s.clampNegativePressure ? 1u : 0u;
  p.neighbourCapacity = s.neighbourCapacity;
  p.dampingRate = s.dampingRate;
  p.dampingUntil = s.dampingUntil;
  p.spsEnabled = s.sps ? 1u : 0u;
  p.spsSmagorinsky = float(double(s.smagorinsky) * s.spacing * double(s.smagorinsky) * s.spacing);
  p.spsBlinn = float(double(s.blinn) * s.spacing * s.spacing);
  p.backgroundPressure = s.backgroundPressure;
  p.backgroundRamp = s.backgroundPressureRamp;
  p.deltaSph = s.densityMethod == DensityMethod::Continuity ? s.deltaSph : 0.0f;
  if (s.pressureSolver == PressureSolver::Dfsph) {
    // No equation of state: the solve gives the pressure, and the step is limited by the
    // flow's speed (C_a h / |v|), not by sound (the repulsion keeps its strength from c0).
    // B stays: the density pass's pressure follows the Tait law on expansion (common/tait.glsl).
    p.pressureSolver = 1u;
    p.c0 = 0.0f;
    p.solveFloor = float(0.25 * s.stiffnessDenominatorAtRest());
    p.solveCompliance = s.solverCompressible ? float(1.0 / (double(s.soundSpeed) * s.soundSpeed)) : 0.0f;
  }
  for (int a = 0; a < 3; ++a) p.gravityOnly[a] = s.gravity[a];
  return p;
}

TileGrid TileGrid::covering(glm::vec3 lo, glm::vec3 hi, std::uint32_t periodicAxes, float minSize, float support,
                           float skin) {
  require(finitePositive(minSize) && minSize > support, "tile size must exceed the kernel support");
  TileGrid g{};
  for (float size = minSize;; size *= 1.25f) {
    float allowed = 3.0e38f;  // the smallest tile of an axis with non-neighbouring tiles
    for (int a = 0; a < 3; ++a) {
      const float extent = hi[a] - lo[a];
      require(std::isfinite(extent) && extent > 0.0f, "the domain must have a positive extent");
      const double n = std::floor(double(extent) / size);
      g.count[a] = std::uint32_t(std::clamp(n, 1.0, double(kMaxTiles)));
      g.origin[a] = lo[a];
      g.invSize[a] = float(double(g.count[a]) / extent);
      if (g.count[a] >= 3) allowed = std::min(allowed, extent / float(g.count[a]));
    }
    g.count[3] = periodicAxes & 7u;
    // (a hundred-thousandth less: the tiles' edges are float products)
    g.origin[3] = allowed < 3.0e38f ? 0.5f * (allowed * (1.0f - 1.0e-5f) - support) : 3.0e38f;
    g.invSize[3] = skin * skin;
    if (std::uint64_t(g.count[0]) * g.count[1] * g.count[2] <= kMaxTiles) return g;
  }
}

glm::uvec3 TileGrid::cellOf(glm::vec3 x) const {
  glm::uvec3 c;
  for (int a = 0; a < 3; ++a) {
    const float t = std::floor((x[a] - origin[a]) * invSize[a]);
    const float clamped = std::clamp(t, -1.0f, float(count[a]));
    c[a] = std::uint32_t(std::clamp(int(clamped), 0, int(count[a]) - 1));
  }
  return c;
}

namespace {
// The list build (sph/build_list.comp) scans the 5 x 5 rows of cells along x around a
// particle's cell, skips the rows whose nearest point is the list radius R or more away in
// (y, z), and trims each row's x-cells to the remaining reach sqrt(R^2 - gy^2 - gz^2). Cells
// are a quarter of R along x, so the trimmed rows hold few candidates beyond the sphere, and
// two thirds of R along y and z, the widest for which five rows still reach R, so fewer rows
// remain: a dam-break list pass 10% cheaper than with cells of R / 2 on all axes (which test
// about half the candidates of the 27 cells of R), at the same sort cost (the dam break,
// hemo-bench speed on lavapipe). A periodic y or z axis too short for five such cells gets cells of R / 2
// (five distinct rows need a period of 2.5 R). Two parts: the fluid's slots first, so the
// fluid passes' SIMD groups hold fluid only (mixed groups ran their boundary lanes idle: 16%
// of the dam break's fluid lanes).
GridSpec gridFor(glm::vec3 lo, glm::vec3 hi, const SphSettings& s) {
  s.validate();
  const float radius = s.listRadius();
  glm::vec3 scale(1.0f, 8.0f / 3.0f, 8.0f / 3.0f);  // cells of R/4, 2R/3, 2R/3
  const GridSpec wide = GridSpec::covering(lo, hi, 0.25f * radius, s.periodic, scale);
  for (int a = 1; a < 3; ++a) {
    if (wide.periodic(a) && wide.dims[a] < 5) scale[a] = 2.0f;  // R/2
  }
  GridSpec spec = GridSpec::covering(lo, hi, 0.25f * radius, s.periodic, scale);
  spec.parts = 2;
  spec.validate();
  for (int a = 0; a < 3; ++a) {
    // x: the cells within R either way of a particle's (four of R/4) distinct; y, z: five rows
    const std::uint32_t needed = a == 0 ? 9u : 5u;
    if (spec.periodic(a) && spec.dims[a] < needed) {
      throw std::invalid_argument(std::string("periodic axis ") + "xyz"[a] + " of " + std::to_string(spec.period[a]) +
                                  " m is shorter than 2.5 neighbour-list radii (" +
                                  std::to_string(2.5f * radius) + " m)");
    }
  }
  return spec;
}

// The tile test's grid: tiles of at least 1.5 list radii over the domain (on periodic axes the
// grid's period). Replayed offline on the whole dam break (positions of every step), the
// reach test alone rebuilt 860 times, with tiles of 1.5 R 731 times, of 2 R 750 (the tiles
// alone).
TileGrid tilesFor(const GridSpec& spec, glm::vec3 lo, glm::vec3 hi, const SphSettings& s) {
  std::uint32_t periodic = 0;
  for (int a = 0; a < 3; ++a) {
    if (spec.periodic(a)) {
      periodic |= 1u << a;
      lo[a] = spec.origin[a];
      hi[a] = spec.origin[a] + spec.period[a];
    }
  }
  return TileGrid::covering(lo, hi, periodic, 1.5f * s.listRadius(), s.supportRadius(),
                            s.listRadius() - s.supportRadius());
}
}  // namespace

SphSolver::SphSolver(gpu::Context& context, ParticleStore& particles, glm::vec3 domainMin, glm::vec3 domainMax,
                     const SphSettings& requested, std::uint32_t maxStepsPerBatch)
    : context_(&context),
      particles_(&particles),
      settings_(resolveNeighbourSearch(context, particles, requested)),
      params_(makeParams(settings_)),
      maxStepsPerBatch_(std::max(maxStepsPerBatch, 1u)),
      grid_(context, gridFor(domainMin, domainMax, settings_), particles),
      paramsBuffer_(context, sizeof(SphParams), gpu::MemoryUse::Device, "sph params"),
      state_(context, perParticle(particles, 16), gpu::MemoryUse::Device, "sph state"),
      accel_(context, perParticle(particles, 16), gpu::MemoryUse::Device, "sph accel"),
      dtLimit_(context, perParticle(particles, 4), gpu::MemoryUse::Device, "sph dt limits"),
      // (a texel's worth when the passes walk cells and keep no list)
      ncount_(context, settings_.neighbourSearch == NeighbourSearch::Cells ? 16 : perParticle(particles, 4),
              gpu::MemoryUse::Device, "neighbour counts"),
      pairCount_(context, settings_.neighbourSearch == NeighbourSearch::Cells ? 16 : perParticle(particles, 4),
                 gpu::MemoryUse::Device, "interacting pair counts"),
      viscousVel_(context, perParticle(particles, 16), gpu::MemoryUse::Device, "viscous velocities"),
      clusterCapacity_(clusterEntries(settings_.neighbourCapacity)),
      // (a texel's worth when the solver does not use them)
      ccount_(context, clusterLayout(context, settings_, particles) ? clustersFor(particles) * 4 : 16,
              gpu::MemoryUse::Device, "cluster list counts"),
      clist_(context, clusterLayout(context, settings_, particles) ? clustersFor(particles) * 4 * clusterCapacity_ : 16,
             gpu::MemoryUse::Device, "cluster lists"),
      corder_(context, clusterLayout(context, settings_, particles) ? clustersFor(particles) * 4 : 16,
              gpu::MemoryUse::Device, "cluster walk order"),
      pairPosition_(context, perParticle(particles, 16), gpu::MemoryUse::Device, "pair positions (x, V p)"),
      activeSlots_(context, perParticle(particles, 4), gpu::MemoryUse::Device, "boundary slots with fluid neighbours"),
      activeArgs_(context, activeArgsBytes(context, settings_, particles), gpu::MemoryUse::Device,
                  "boundary-pressure indirect arguments"),
      activeAppended_(context, clusterLayout(context, settings_, particles) ? clustersFor(particles) * 4 : 16,
                      gpu::MemoryUse::Device, "boundary clusters' active list as appended"),
      integrateArgs_(context, 32, gpu::MemoryUse::Device, "integrator indirect arguments"),
      clock_(context, 32, gpu::MemoryUse::Device, "sph clock"),
      status_(context, HEMO_STATUS_COUNT * 4, gpu::MemoryUse::Device, "sph status"),
      log_(context, std::uint64_t(maxStepsPerBatch_) * 8, gpu::MemoryUse::Device, "sph step log"),
      inflow_(context, sizeof(InflowParams), gpu::MemoryUse::Device, "inflow params"),
      // (the RK2 stages only: a texel's worth for symplectic Euler, whose pipelines leave them out)
      savedPos_(context, settings_.integrator == Integrator::Rk2Midpoint ? perParticle(particles, 16) : 16,
                gpu::MemoryUse::Device, "rk2 saved positions"),
      savedVel_(context, settings_.integrator == Integrator::Rk2Midpoint ? perParticle(particles, 16) : 16,
                gpu::MemoryUse::Device, "rk2 saved velocities"),
      stepDt_(context, 4, gpu::MemoryUse::Device, "step dt"),
      tauA_(context, settings_.sps ? perParticle(particles, 16) : 16, gpu::MemoryUse::Device, "sps tau a"),
      tauB_(context, settings_.sps ? perParticle(particles, 16) : 16, gpu::MemoryUse::Device, "sps tau b"),
      viscosity_(context, settings_.nonNewtonian() ? perParticle(particles, 4) : 4, gpu::MemoryUse::Device, "viscosity"),
      // Partials for the force pass's SIMD groups over all slots and the wall stage's over the
      // non-fluid ones.
      dtPartials_(context, 2 * partialsPerPass(particles) * 8, gpu::MemoryUse::Device, "time-step partials"),
      dtCounts_(context, 16, gpu::MemoryUse::Device, "time-step partials written"),
      dtResult_(context, 8, gpu::MemoryUse::Device, "time-step limits (min, max)"),
      // One partial per SIMD group of the integrator.
      checkPartials_(context, partialsPerPass(particles) * 16,
                     gpu::MemoryUse::Device, "rebuild check partials"),
      checkCount_(context, 4, gpu::MemoryUse::Device, "rebuild check partials written"),
      checkResult_(context, 16, gpu::MemoryUse::Device, "rebuild check result"),
      tileSpec_(tilesFor(grid_.spec(), domainMin, domainMax, settings_)),
      tileGrid_(context, sizeof(TileGrid), gpu::MemoryUse::Device, "rebuild tile grid"),
      tileBoxes_(context, std::uint64_t(tileSpec_.tiles()) * HEMO_TILE_WORDS * 4, gpu::MemoryUse::Device,
                 "rebuild tile boxes"),
      tileResult_(context, 4, gpu::MemoryUse::Device, "rebuild tile result"),
      tileOccupied_(context, (std::uint64_t(tileSpec_.tiles()) + 2) * 4, gpu::MemoryUse::Device, "rebuild tiles occupied"),
      rebuildGate_(context, checkResult_, rebuildGateSlots(context, settings_, particles), "neighbour rebuild", 2),
      kappa_(context, settings_.pressureSolver == PressureSolver::Dfsph ? perParticle(particles, 16) : 16,
             gpu::MemoryUse::Device, "dfsph stiffness and pressure (k, p, divergence sum of k, density solve's p)"),
      solvePartials_(context, 16, gpu::MemoryUse::Device, "dfsph error partials"),
      solveStats_(context, 2 * HEMO_DFSPH_STAT_COUNT * 4, gpu::MemoryUse::Device, "dfsph stats"),
      // (a correction and a prediction per region; the density solve's regions, the divergence solve's)
      pressureGate_(context, solveStats_, 4, "pressure solve", 2),
      solveDepth_(context, HEMO_DFSPH_DEPTH_COUNT * 4, gpu::MemoryUse::Device, "dfsph recorded depth"),
      recordedIterations_(settings_.solverMaxIterations),
      openCounters_(context, HEMO_OPEN_COUNTER_COUNT * 4, gpu::MemoryUse::Device, "open ends' counters"),
      pending_(context, perParticle(particles, 4), gpu::MemoryUse::Device, "open inlet's crossers owed an image"),
      openSums_(context, kOpenProfile * kOpenSumWords * 4, gpu::MemoryUse::Device, "open ends' speed sums"),
      openProfile_(context, kOpenProfile * 4, gpu::MemoryUse::Device, "open ends' speed profiles"),
      escapeMask_(context, settings_.parkedSlots ? EscapeGrid::over(domainMin, domainMax, settings_.spacing).words() * 4 : 4,
                  gpu::MemoryUse::Device, "open ends' escape mask") {
  const SphSettings& settings = settings_;  // (Auto resolved)
  cellWalk_ = settings.neighbourSearch == NeighbourSearch::Cells;
  const bool contiguous = contiguousList(context, settings);
  clusters_ = clusterLayout(context, settings, particles);
  // The lists in pages of pageSlots_ slots, each its own buffer (one page when one buffer
  // passes no binding limit): entry k of slot i is entry (i & mask) * particleStride +
  // k * listStride of its page's buffer, the interleaved layout's stride being the page's slots.
  // Walking cells, the lists are a texel's worth each, one page of all slots.
  const std::uint32_t slots = std::max(particles.capacity(), 1u);
  pageSlots_ = cellWalk_ ? slots : listPageSlotsFor(context, settings, slots);
  const std::uint32_t pages = listPagesFor(context, settings, particles);
  auto pageEntries = [&](std::uint32_t p) {
    return cellWalk_ ? 4 : listPageEntries(context, settings, slots, pageSlots_, p);
  };
  params_.listStride = contiguous ? 1u : pageSlots_;
  params_.listParticleStride = contiguous ? settings.neighbourCapacity : 1u;
  params_.listPageMask = pages > 1 ? pageSlots_ - 1u : ~0u;
  // The lists are the largest buffers and the last the solver makes: what the device's memory
  // must hold is known here, within a few percent, before they are allocated.
  std::uint64_t listBytes = 0;
  for (std::uint32_t p = 0; p < pages; ++p) listBytes += 2 * 4 * pageEntries(p);  // the list and the pairs
  const std::uint64_t held = context.deviceMemoryBytes();
  if (!cellWalk_ && held + listBytes > context.deviceMemoryCapacity()) {
    auto gib = [](std::uint64_t bytes) {
      char text[32];
      std::snprintf(text, sizeof text, "%.3f GiB", double(bytes) / double(1ull << 30));
      return std::string(text);
    };
    throw gpu::OutOfDeviceMemory(
        "the device's memory cannot hold the neighbour list and the interacting pairs of " + std::to_string(slots) +
            " particles (" + std::to_string(settings.neighbourCapacity) + " entries each): " + gib(listBytes) +
            ", with the " + gib(held) + " hemo already holds: the scene needs about " + gib(held + listBytes) +
            " and the device has " + gib(context.deviceMemoryCapacity()) +
            " (particles.neighbour_search \"cells\" keeps no list; or fewer particles, a smaller particles.neighbour_capacity"
            " or smoothing_ratio, or a device with more memory)",
        held + listBytes, context.deviceMemoryCapacity());
  }
  for (std::uint32_t p = 0; p < pages; ++p) {
    const std::uint64_t entries = pageEntries(p);
    const std::string page = cellWalk_ ? " (none: the passes walk cells)"
                             : pages > 1 ? " (page " + std::to_string(p) + " of " + std::to_string(pages) + ")"
                                         : "";
    nlist_.emplace_back(context, entries * 4, gpu::MemoryUse::Device, "neighbour list" + page);
    pairList_.emplace_back(context, entries * 4, gpu::MemoryUse::Device, "interacting pairs" + page);
  }
  // Specialization constant 2 of the pair passes: list entries per texel read.
  listWidth_ = listReadWidthFor(context, settings);
  const VkFormat listFormat = listWidth_ == 4u ? gpu::texel::kUvec4 : gpu::texel::kUint;
  // A pair pass's list bindings: its counts and the entries of page p; walking cells, the
  // grid's positions at build (as RGBA32UI texels) and its cellStart in their slots
  // (common/cell_walk.glsl).
  auto countsAt = [&](std::uint32_t slot, const gpu::Buffer* counts) {
    return cellWalk_ ? gpu::texelBinding(slot, &grid_.positionsAtBuild(), gpu::texel::kUvec4)
                     : gpu::texelBinding(slot, counts, gpu::texel::kUint);
  };
  auto listAt = [&](std::uint32_t slot, const gpu::Buffer* page) {
    return cellWalk_ ? gpu::texelBinding(slot, &grid_.cellStart(), gpu::texel::kUint)
                     : gpu::texelBinding(slot, page, listFormat);
  };
  for (int a = 0; a < 3; ++a) {
    if (grid_.spec().periodic(a)) periodicAxes_ |= 1u << a;
  }
  const GridSpec& spec = grid_.spec();
  for (int a = 0; a < 3; ++a) {
    params_.origin[a] = spec.origin[a];
    params_.period[a] = spec.period[a];
    params_.invPeriod[a] = spec.periodic(a) ? 1.0f / spec.period[a] : 0.0f;
  }
  const NeighbourGrid::Push gridPush = grid_.push(0);
  for (int a = 0; a < 4; ++a) {
    params_.gridOrigin[a] = gridPush.origin[a];
    params_.gridInvCell[a] = gridPush.invCell[a];
    params_.gridDims[a] = a < 3 ? gridPush.dims[a] : 0u;
    params_.gridPeriodic[a] = gridPush.periodic[a];
  }
  paramsBuffer_.upload(std::vector<SphParams>{params_});
  inflow_.upload(std::vector<InflowParams>{disabledInflowParams()});
  auto& cache = context.pipelines();
  // The pair passes' modules: walking cells, their variants compiled for it (interface/sph.h).
  auto pairPass = [&](const char* name) { return cellWalk_ ? std::string(name) + "_cells" : std::string(name); };
  buildList_ = &cache.get({"sph/build_list", HEMO_BUILD_BINDING_COUNT, sizeof(BuildPush), kWorkgroup,
                           pairSpecialization({}), 1u << HEMO_BUILD_BINDING_PARAMS,
                             1u << HEMO_BUILD_BINDING_POSITIONS | 1u << HEMO_BUILD_BINDING_CELL_START});
  // Constant 1 of the density pass and the integrator: summation density (0), or continuity
  // density advanced by the density pass (1, symplectic Euler) or by the RK2 stages (2).
  const std::uint32_t continuity = settings.densityMethod == DensityMethod::Summation ? 0u
                                   : settings.integrator == Integrator::Rk2Midpoint  ? 2u
                                                                                     : 1u;
  density_ = &cache.get({pairPass("sph/density"), HEMO_DENSITY_BINDING_COUNT, sizeof(DensityPush), kWorkgroup, pairSpecialization({continuity, listWidth_}),
                         1u << HEMO_DENSITY_BINDING_PARAMS | 1u << HEMO_DENSITY_BINDING_CLOCK | 1u << HEMO_DENSITY_BINDING_INFLOW,
                         1u << HEMO_DENSITY_BINDING_POSITIONS | 1u << HEMO_DENSITY_BINDING_VELOCITIES |
                             1u << HEMO_DENSITY_BINDING_NCOUNT | 1u << HEMO_DENSITY_BINDING_NLIST |
                             1u << HEMO_DENSITY_BINDING_NORMALS});
  boundaryPressure_ = &cache.get({pairPass("sph/boundary_pressure"), HEMO_BPRESSURE_BINDING_COUNT, sizeof(BoundaryPush), kWorkgroup, pairSpecialization({listWidth_}),
                                  1u << HEMO_BPRESSURE_BINDING_PARAMS | 1u << HEMO_BPRESSURE_BINDING_CLOCK,
                                  1u << HEMO_BPRESSURE_BINDING_POSITIONS | 1u << HEMO_BPRESSURE_BINDING_VELOCITIES |
                                      1u << HEMO_BPRESSURE_BINDING_NCOUNT | 1u << HEMO_BPRESSURE_BINDING_NLIST |
                                      1u << HEMO_BPRESSURE_BINDING_FLUID_STATE});
  // constants 1: the list's read width; 2: the SPS stress; 3: the non-Newtonian viscosity
  const std::uint32_t variableViscosity = settings.nonNewtonian() ? 1u : 0u;
  spsStress_ = &cache.get({pairPass("sph/sps_stress"), HEMO_SPS_BINDING_COUNT, sizeof(SpsPush), kWorkgroup,
                           pairSpecialization({listWidth_, settings.sps ? 1u : 0u, variableViscosity}), 1u << HEMO_SPS_BINDING_PARAMS,
                           1u << HEMO_SPS_BINDING_POSITIONS | 1u << HEMO_SPS_BINDING_VELOCITIES | 1u << HEMO_SPS_BINDING_STATE |
                               1u << HEMO_SPS_BINDING_NCOUNT | 1u << HEMO_SPS_BINDING_NLIST | 1u << HEMO_SPS_BINDING_VISCOUS_VEL});
  // constant 1: the SPS term compiled in or out; 2: the list's read width; 3: the
  // non-Newtonian viscosity
  dtReduce_ = &cache.get({"sph/dt_reduce", HEMO_DTREDUCE_BINDING_COUNT, sizeof(DtReducePush), kWorkgroup, {},
                          1u << HEMO_DTREDUCE_BINDING_TOOLS,
                          1u << HEMO_DTREDUCE_BINDING_PARTIALS | 1u << HEMO_DTREDUCE_BINDING_TOOL_PARTIALS});
  forces_ = &cache.get({pairPass("sph/forces"), HEMO_FORCES_BINDING_COUNT, sizeof(ForcesPush), kWorkgroup,
                        pairSpecialization({settings.sps ? 1u : 0u, listWidth_, variableViscosity}), 1u << HEMO_FORCES_BINDING_PARAMS,
                        1u << HEMO_FORCES_BINDING_POSITIONS | 1u << HEMO_FORCES_BINDING_VELOCITIES | 1u << HEMO_FORCES_BINDING_STATE |
                            1u << HEMO_FORCES_BINDING_NCOUNT | 1u << HEMO_FORCES_BINDING_NORMALS | 1u << HEMO_FORCES_BINDING_NLIST | 1u << HEMO_FORCES_BINDING_TAU_A |
                            1u << HEMO_FORCES_BINDING_TAU_B | 1u << HEMO_FORCES_BINDING_VISCOUS_VEL |
                            1u << HEMO_FORCES_BINDING_PAIR_POSITION | 1u << HEMO_FORCES_BINDING_VISCOSITY});
  // constant 2: the stage (symplectic Euler, or RK2's two), one pipeline each; constant 3: the
  // inflow zone's code compiled in or out (llvmpipe runs a branch's body under an empty lane
  // mask: the zone's test, waveform and mass supply cost the dam break's integrator about a
  // sixth on lavapipe). All their sets' layouts are identical, so one
  // descriptor set serves them all.
  continuity_ = continuity;
  for (std::uint32_t mode = 0; mode < 3; ++mode) integratePipeline(mode, 0u);
  integratePipeline(HEMO_INTEGRATE_SYMPLECTIC_EULER, 0u, true);
  tileStatic_ = &cache.get({"sph/tile_static", HEMO_TILE_STATIC_BINDING_COUNT, sizeof(CountPush), kWorkgroup, {},
                            1u << HEMO_TILE_STATIC_BINDING_TILE_GRID,
                            1u << HEMO_TILE_STATIC_BINDING_POSITIONS | 1u << HEMO_TILE_STATIC_BINDING_VELOCITIES});
  // constant 1: the tile test (after symplectic Euler) or the reach test alone (after RK2)
  for (std::uint32_t tiles = 0; tiles < 2; ++tiles) {
    rebuildDecide_[tiles] = &cache.get({"sph/rebuild_decide", HEMO_DECIDE_BINDING_COUNT, sizeof(DecidePush), kWorkgroup, {tiles},
                                        1u << HEMO_DECIDE_BINDING_TILE_GRID,
                                        1u << HEMO_DECIDE_BINDING_CHECK_PARTIALS | 1u << HEMO_DECIDE_BINDING_TILE_BOXES_IN});
  }
  const ParticleArrays& a = particles.live();
  tileStaticSet_ = tileStatic_->makeSet({gpu::texelBinding(HEMO_TILE_STATIC_BINDING_POSITIONS, &a.positions, gpu::texel::kVec4),
                                         gpu::texelBinding(HEMO_TILE_STATIC_BINDING_VELOCITIES, &a.velocities, gpu::texel::kVec4),
                                         {HEMO_TILE_STATIC_BINDING_TILE_GRID, &tileGrid_},
                                         {HEMO_TILE_STATIC_BINDING_TILE_BOXES, &tileBoxes_}});
  // Per page of the list: its buffers, its part of the boundary pass's active list and its
  // indirect arguments (one page: the whole of each).
  auto activeArgsOf = [&](std::uint32_t page) {
    return gpu::Binding{0, &activeArgs_, pages > 1 ? kActiveArgsStride * page : 0, 16};
  };
  auto activeSlotsOf = [&](std::uint32_t page) {
    const std::uint64_t first = std::uint64_t(page) * pageSlots_;
    return gpu::Binding{0, &activeSlots_, pages > 1 ? first * 4 : 0,
                        pages > 1 ? std::min<std::uint64_t>(pageSlots_, slots - first) * 4 : VK_WHOLE_SIZE};
  };
  auto at = [](gpu::Binding b, std::uint32_t slot) {
    b.slot = slot;
    return b;
  };
  for (std::uint32_t p = 0; p < pages; ++p) {
    buildListSets_.push_back(buildList_->makeSet({gpu::texelBinding(HEMO_BUILD_BINDING_POSITIONS, &grid_.positionsAtBuild(), gpu::texel::kVec4),
                                                  gpu::texelBinding(HEMO_BUILD_BINDING_CELL_START, &grid_.cellStart(), gpu::texel::kUint),
                                                  {HEMO_BUILD_BINDING_PARAMS, &paramsBuffer_},
                                                  {HEMO_BUILD_BINDING_NCOUNT, &ncount_},
                                                  {HEMO_BUILD_BINDING_NLIST, &nlist_[p]},
                                                  {HEMO_BUILD_BINDING_STATUS, &status_},
                                                  at(activeArgsOf(p), HEMO_BUILD_BINDING_ACTIVE_ARGS)}));
  }
  boundaryClusters_ = &cache.get({"sph/boundary_clusters", HEMO_BPRESSURE_BINDING_COUNT, sizeof(BoundaryClusterPush), kWorkgroup,
                                  pairSpecialization({}), 1u << HEMO_BPRESSURE_BINDING_PARAMS | 1u << HEMO_BPRESSURE_BINDING_CLOCK,
                                  1u << HEMO_BPRESSURE_BINDING_POSITIONS | 1u << HEMO_BPRESSURE_BINDING_VELOCITIES |
                                      1u << HEMO_BPRESSURE_BINDING_NCOUNT | 1u << HEMO_BPRESSURE_BINDING_NLIST |
                                      1u << HEMO_BPRESSURE_BINDING_FLUID_STATE});
  buildClusters_ = &cache.get({"sph/build_clusters", HEMO_CBUILD_BINDING_COUNT, sizeof(ClusterBuildPush), kWorkgroup,
                               pairSpecialization({}), 1u << HEMO_CBUILD_BINDING_PARAMS,
                               1u << HEMO_CBUILD_BINDING_POSITIONS | 1u << HEMO_CBUILD_BINDING_CELL_START});
  clusterOrder_ = &cache.get({"sph/cluster_order", HEMO_CORDER_BINDING_COUNT, sizeof(ClusterOrderPush), kWorkgroup, {}, 0u,
                              1u << HEMO_CORDER_BINDING_CCOUNT | 1u << HEMO_CORDER_BINDING_ITEMS});
  densityClusters_ = &cache.get({"sph/density_clusters", HEMO_CDENSITY_BINDING_COUNT, sizeof(ClusterPush), kWorkgroup,
                                 pairSpecialization({}), 1u << HEMO_CDENSITY_BINDING_PARAMS | 1u << HEMO_CDENSITY_BINDING_CLOCK,
                                 1u << HEMO_CDENSITY_BINDING_POSITIONS | 1u << HEMO_CDENSITY_BINDING_VELOCITIES |
                                     1u << HEMO_CDENSITY_BINDING_CCOUNT | 1u << HEMO_CDENSITY_BINDING_CLIST |
                                     1u << HEMO_CDENSITY_BINDING_ORDER});
  forcesClusters_ = &cache.get({"sph/forces_clusters", HEMO_CFORCES_BINDING_COUNT, sizeof(ClusterPush), kWorkgroup,
                                pairSpecialization({}), 1u << HEMO_CFORCES_BINDING_PARAMS,
                                1u << HEMO_CFORCES_BINDING_POSITIONS | 1u << HEMO_CFORCES_BINDING_VELOCITIES |
                                    1u << HEMO_CFORCES_BINDING_NORMALS | 1u << HEMO_CFORCES_BINDING_STATE |
                                    1u << HEMO_CFORCES_BINDING_CCOUNT | 1u << HEMO_CFORCES_BINDING_CLIST |
                                    1u << HEMO_CFORCES_BINDING_VISCOUS_VEL | 1u << HEMO_CFORCES_BINDING_PAIR_POSITION |
                                    1u << HEMO_CFORCES_BINDING_ORDER});
  forcesClustersSet_ = forcesClusters_->makeSet({gpu::texelBinding(HEMO_CFORCES_BINDING_POSITIONS, &a.positions, gpu::texel::kVec4),
                                 gpu::texelBinding(HEMO_CFORCES_BINDING_VELOCITIES, &a.velocities, gpu::texel::kVec4),
                                 gpu::texelBinding(HEMO_CFORCES_BINDING_NORMALS, &a.normals, gpu::texel::kVec4),
                                 {HEMO_CFORCES_BINDING_PARAMS, &paramsBuffer_},
                                 gpu::texelBinding(HEMO_CFORCES_BINDING_STATE, &state_, gpu::texel::kVec4),
                                 gpu::texelBinding(HEMO_CFORCES_BINDING_CCOUNT, &ccount_, gpu::texel::kUint),
                                 gpu::texelBinding(HEMO_CFORCES_BINDING_CLIST, &clist_, gpu::texel::kUvec4),
                                 {HEMO_CFORCES_BINDING_ACCEL, &accel_},
                                 {HEMO_CFORCES_BINDING_DT_LIMIT, &dtLimit_},
                                 {HEMO_CFORCES_BINDING_DT_PARTIALS, &dtPartials_},
                                 {HEMO_CFORCES_BINDING_DT_COUNTS, &dtCounts_},
                                 {HEMO_CFORCES_BINDING_IDS, &a.ids},
                                 {HEMO_CFORCES_BINDING_STATUS, &status_},
                                 gpu::texelBinding(HEMO_CFORCES_BINDING_VISCOUS_VEL, &viscousVel_, gpu::texel::kVec4),
                                 gpu::texelBinding(HEMO_CFORCES_BINDING_PAIR_POSITION, &pairPosition_, gpu::texel::kVec4),
                                 gpu::texelBinding(HEMO_CFORCES_BINDING_ORDER, &corder_, gpu::texel::kUint)});
  buildClustersSet_ = buildClusters_->makeSet({gpu::texelBinding(HEMO_CBUILD_BINDING_POSITIONS, &grid_.positionsAtBuild(), gpu::texel::kVec4),
                                               gpu::texelBinding(HEMO_CBUILD_BINDING_CELL_START, &grid_.cellStart(), gpu::texel::kUint),
                                               {HEMO_CBUILD_BINDING_PARAMS, &paramsBuffer_},
                                               {HEMO_CBUILD_BINDING_CCOUNT, &ccount_},
                                               {HEMO_CBUILD_BINDING_CLIST, &clist_},
                                               {HEMO_CBUILD_BINDING_STATUS, &status_},
                                               {HEMO_CBUILD_BINDING_ACTIVE_ARGS, &activeArgs_}});
  densityClustersSet_ = densityClusters_->makeSet({gpu::texelBinding(HEMO_CDENSITY_BINDING_POSITIONS, &a.positions, gpu::texel::kVec4),
                                   gpu::texelBinding(HEMO_CDENSITY_BINDING_VELOCITIES, &a.velocities, gpu::texel::kVec4),
                                   {HEMO_CDENSITY_BINDING_PARAMS, &paramsBuffer_},
                                   {HEMO_CDENSITY_BINDING_STATE, &state_},
                                   gpu::texelBinding(HEMO_CDENSITY_BINDING_CCOUNT, &ccount_, gpu::texel::kUint),
                                   gpu::texelBinding(HEMO_CDENSITY_BINDING_CLIST, &clist_, gpu::texel::kUvec4),
                                   {HEMO_CDENSITY_BINDING_CLOCK, &clock_},
                                   {HEMO_CDENSITY_BINDING_VISCOUS_VEL, &viscousVel_},
                                   {HEMO_CDENSITY_BINDING_PAIR_POSITION, &pairPosition_},
                                   gpu::texelBinding(HEMO_CDENSITY_BINDING_ORDER, &corder_, gpu::texel::kUint)});
  // the fluid clusters' walk order, and the boundary clusters' active list sorted into the one
  // the evaluations walk
  auto orderSetFor = [&](const gpu::Buffer* order) {
    return clusterOrder_->makeSet({gpu::texelBinding(HEMO_CORDER_BINDING_CCOUNT, &ccount_, gpu::texel::kUint),
                                   {HEMO_CORDER_BINDING_ORDER, order},
                                   gpu::texelBinding(HEMO_CORDER_BINDING_ITEMS, &activeAppended_, gpu::texel::kUint),
                                   {HEMO_CORDER_BINDING_ACTIVE_ARGS, &activeArgs_}});
  };
  clusterOrderSet_ = orderSetFor(&corder_);
  boundaryOrderSet_ = orderSetFor(&activeSlots_);
  for (std::uint32_t p = 0; p < pages; ++p) {
    densitySets_.push_back(density_->makeSet({gpu::texelBinding(HEMO_DENSITY_BINDING_POSITIONS, &a.positions, gpu::texel::kVec4),
                                              gpu::texelBinding(HEMO_DENSITY_BINDING_VELOCITIES, &a.velocities, gpu::texel::kVec4),
                                              {HEMO_DENSITY_BINDING_PARAMS, &paramsBuffer_},
                                              {HEMO_DENSITY_BINDING_STATE, &state_},
                                              countsAt(HEMO_DENSITY_BINDING_NCOUNT, &ncount_),
                                              listAt(HEMO_DENSITY_BINDING_NLIST, &nlist_[p]),
                                              {HEMO_DENSITY_BINDING_CLOCK, &clock_},
                                              {HEMO_DENSITY_BINDING_VISCOUS_VEL, &viscousVel_},
                                              gpu::texelBinding(HEMO_DENSITY_BINDING_NORMALS, &a.normals, gpu::texel::kVec4),
                                              {HEMO_DENSITY_BINDING_PAIR_POSITION, &pairPosition_},
                                              {HEMO_DENSITY_BINDING_PAIR_COUNT, &pairCount_},
                                              {HEMO_DENSITY_BINDING_PAIR_LIST, &pairList_[p]},
                                              {HEMO_DENSITY_BINDING_INFLOW, &inflow_},
                                              {HEMO_DENSITY_BINDING_OPEN_PROFILE, &openProfile_}}));
  }
  // The boundary-pressure pass and its cluster form share their bindings but for the lists.
  auto boundarySetFor = [&](const gpu::ComputePipeline& pipeline, gpu::Binding counts, gpu::Binding list,
                            gpu::Binding active, gpu::Binding args) {
    return pipeline.makeSet({gpu::texelBinding(HEMO_BPRESSURE_BINDING_POSITIONS, &a.positions, gpu::texel::kVec4),
                             gpu::texelBinding(HEMO_BPRESSURE_BINDING_VELOCITIES, &a.velocities, gpu::texel::kVec4),
                             gpu::texelBinding(HEMO_BPRESSURE_BINDING_FLUID_STATE, &state_, gpu::texel::kVec4),
                             {HEMO_BPRESSURE_BINDING_PARAMS, &paramsBuffer_},
                             {HEMO_BPRESSURE_BINDING_STATE, &state_},
                             counts,
                             list,
                             {HEMO_BPRESSURE_BINDING_VISCOUS_VEL, &viscousVel_},
                             {HEMO_BPRESSURE_BINDING_CLOCK, &clock_},
                             {HEMO_BPRESSURE_BINDING_PAIR_POSITION, &pairPosition_},
                             at(active, HEMO_BPRESSURE_BINDING_ACTIVE),
                             at(args, HEMO_BPRESSURE_BINDING_ACTIVE_ARGS)});
  };
  for (std::uint32_t p = 0; p < pages; ++p) {
    boundarySets_.push_back(boundarySetFor(*boundaryPressure_, countsAt(HEMO_BPRESSURE_BINDING_NCOUNT, &ncount_),
                                           listAt(HEMO_BPRESSURE_BINDING_NLIST, &nlist_[p]), activeSlotsOf(p),
                                           activeArgsOf(p)));
  }
  const gpu::Binding clusterCounts = gpu::texelBinding(HEMO_BPRESSURE_BINDING_NCOUNT, &ccount_, gpu::texel::kUint);
  const gpu::Binding clusterLists = gpu::texelBinding(HEMO_BPRESSURE_BINDING_NLIST, &clist_, gpu::texel::kUvec4);
  boundaryClustersSet_ = boundarySetFor(*boundaryClusters_, clusterCounts, clusterLists, {0, &activeSlots_}, {0, &activeArgs_});
  // (the sorting mode appends to a list of its own, which sph/cluster_order.comp sorts)
  boundaryClustersSortSet_ = boundarySetFor(*boundaryClusters_, clusterCounts, clusterLists, {0, &activeAppended_},
                                            {0, &activeArgs_});
  for (std::uint32_t p = 0; p < pages; ++p) {
    spsSets_.push_back(spsStress_->makeSet({gpu::texelBinding(HEMO_SPS_BINDING_POSITIONS, &a.positions, gpu::texel::kVec4),
                                            gpu::texelBinding(HEMO_SPS_BINDING_VELOCITIES, &a.velocities, gpu::texel::kVec4),
                                            {HEMO_SPS_BINDING_PARAMS, &paramsBuffer_},
                                            gpu::texelBinding(HEMO_SPS_BINDING_STATE, &state_, gpu::texel::kVec4),
                                            countsAt(HEMO_SPS_BINDING_NCOUNT, &pairCount_),
                                            listAt(HEMO_SPS_BINDING_NLIST, &pairList_[p]),
                                            {HEMO_SPS_BINDING_TAU_A, &tauA_},
                                            {HEMO_SPS_BINDING_TAU_B, &tauB_},
                                            {HEMO_SPS_BINDING_VISCOSITY, &viscosity_},
                                            gpu::texelBinding(HEMO_SPS_BINDING_VISCOUS_VEL, &viscousVel_, gpu::texel::kVec4)}));
  }
  makeDtReduceSet();
  for (std::uint32_t p = 0; p < pages; ++p) {
    forcesSets_.push_back(forces_->makeSet({gpu::texelBinding(HEMO_FORCES_BINDING_POSITIONS, &a.positions, gpu::texel::kVec4),
                                            gpu::texelBinding(HEMO_FORCES_BINDING_VELOCITIES, &a.velocities, gpu::texel::kVec4),
                                            gpu::texelBinding(HEMO_FORCES_BINDING_NORMALS, &a.normals, gpu::texel::kVec4),
                                            {HEMO_FORCES_BINDING_PARAMS, &paramsBuffer_},
                                            gpu::texelBinding(HEMO_FORCES_BINDING_STATE, &state_, gpu::texel::kVec4),
                                            countsAt(HEMO_FORCES_BINDING_NCOUNT, &pairCount_),
                                            listAt(HEMO_FORCES_BINDING_NLIST, &pairList_[p]),
                                            {HEMO_FORCES_BINDING_ACCEL, &accel_},
                                            {HEMO_FORCES_BINDING_DT_LIMIT, &dtLimit_},
                                            {HEMO_FORCES_BINDING_DT_PARTIALS, &dtPartials_},
                                            {HEMO_FORCES_BINDING_DT_COUNTS, &dtCounts_},
                                            {HEMO_FORCES_BINDING_IDS, &a.ids},
                                            {HEMO_FORCES_BINDING_STATUS, &status_},
                                            gpu::texelBinding(HEMO_FORCES_BINDING_TAU_A, &tauA_, gpu::texel::kVec4),
                                            gpu::texelBinding(HEMO_FORCES_BINDING_TAU_B, &tauB_, gpu::texel::kVec4),
                                            gpu::texelBinding(HEMO_FORCES_BINDING_VISCOUS_VEL, &viscousVel_, gpu::texel::kVec4),
                                            gpu::texelBinding(HEMO_FORCES_BINDING_PAIR_POSITION, &pairPosition_, gpu::texel::kVec4),
                                            gpu::texelBinding(HEMO_FORCES_BINDING_VISCOSITY, &viscosity_, gpu::texel::kFloat)}));
  }
  integrateSet_ = integrate_[0][HEMO_INTEGRATE_SYMPLECTIC_EULER]->makeSet({{HEMO_INTEGRATE_BINDING_POSITIONS, &a.positions},
                                       {HEMO_INTEGRATE_BINDING_VELOCITIES, &a.velocities},
                                       gpu::texelBinding(HEMO_INTEGRATE_BINDING_ACCEL, &accel_, gpu::texel::kVec4),
                                       {HEMO_INTEGRATE_BINDING_PARAMS, &paramsBuffer_},
                                       {HEMO_INTEGRATE_BINDING_DT, &dtResult_},
                                       {HEMO_INTEGRATE_BINDING_CLOCK, &clock_},
                                       {HEMO_INTEGRATE_BINDING_STATUS, &status_},
                                       {HEMO_INTEGRATE_BINDING_LOG, &log_},
                                       {HEMO_INTEGRATE_BINDING_SAVED_POS, &savedPos_},
                                       {HEMO_INTEGRATE_BINDING_SAVED_VEL, &savedVel_},
                                       {HEMO_INTEGRATE_BINDING_STEP_DT, &stepDt_},
                                       gpu::texelBinding(HEMO_INTEGRATE_BINDING_POS_AT_BUILD, &grid_.positionsAtBuild(), gpu::texel::kVec4),
                                       {HEMO_INTEGRATE_BINDING_DRIFT_RANGE, &checkResult_},
                                       {HEMO_INTEGRATE_BINDING_CHECK_PARTIALS, &checkPartials_},
                                       {HEMO_INTEGRATE_BINDING_CHECK_COUNT, &checkCount_},
                                       {HEMO_INTEGRATE_BINDING_INFLOW, &inflow_},
                                       gpu::texelBinding(HEMO_INTEGRATE_BINDING_STATE, &state_, gpu::texel::kVec4),
                                       gpu::texelBinding(HEMO_INTEGRATE_BINDING_POSITIONS_IN, &a.positions, gpu::texel::kVec4),
                                       gpu::texelBinding(HEMO_INTEGRATE_BINDING_VELOCITIES_IN, &a.velocities, gpu::texel::kVec4),
                                       {HEMO_INTEGRATE_BINDING_NORMALS, &a.normals},
                                       {HEMO_INTEGRATE_BINDING_TILE_GRID, &tileGrid_},
                                       {HEMO_INTEGRATE_BINDING_TILE_BOXES, &tileBoxes_},
                                       {HEMO_INTEGRATE_BINDING_TILE_OCCUPIED, &tileOccupied_},
                                       {HEMO_INTEGRATE_BINDING_OPEN_COUNTERS, &openCounters_},
                                       {HEMO_INTEGRATE_BINDING_PENDING, &pending_},
                                       {HEMO_INTEGRATE_BINDING_OPEN_SUMS, &openSums_},
                                       {HEMO_INTEGRATE_BINDING_OPEN_PROFILE, &openProfile_},
                                       {HEMO_INTEGRATE_BINDING_ESCAPE_MASK, &escapeMask_}});
  // (both variants' layouts are the same: one set serves them)
  rebuildDecideSet_ = rebuildDecide_[1]->makeSet({{HEMO_DECIDE_BINDING_TILE_GRID, &tileGrid_},
                                                  {HEMO_DECIDE_BINDING_TILE_BOXES, &tileBoxes_},
                                                  {HEMO_DECIDE_BINDING_TILE_OCCUPIED, &tileOccupied_},
                                                  {HEMO_DECIDE_BINDING_CHECK_RESULT, &checkResult_},
                                                  {HEMO_DECIDE_BINDING_TILE_RESULT, &tileResult_},
                                                  {HEMO_DECIDE_BINDING_GATE_ARMED, &rebuildGate_.armedCounts()},
                                                  {HEMO_DECIDE_BINDING_GATE_ARGS, &rebuildGate_.arguments()},
                                                  {HEMO_DECIDE_BINDING_GATE_OPENED, &rebuildGate_.openings()},
                                                  gpu::texelBinding(HEMO_DECIDE_BINDING_CHECK_PARTIALS, &checkPartials_, gpu::texel::kVec4),
                                                  {HEMO_DECIDE_BINDING_CHECK_COUNT, &checkCount_},
                                                  {HEMO_DECIDE_BINDING_INTEGRATE_ARGS, &integrateArgs_},
                                                  gpu::texelBinding(HEMO_DECIDE_BINDING_TILE_BOXES_IN, &tileBoxes_, gpu::texel::kUvec4)});
  if (settings.pressureSolver == PressureSolver::Dfsph) {
    if (pages > 1) {
      throw std::invalid_argument("the DFSPH pressure solver needs the neighbour list in one buffer; the list of " +
                                  std::to_string(slots) + " particles needs " + std::to_string(pages) +
                                  " pages on this device (use the WCSPH solver, or fewer particles)");
    }
    dfsphPredict_ = &cache.get({"sph/dfsph_predict", HEMO_DFSPH_BINDING_COUNT, sizeof(DfsphPredictPush), kWorkgroup,
                                pairSpecialization({listWidth_}),
                                1u << HEMO_DFSPH_BINDING_PARAMS | 1u << HEMO_DFSPH_BINDING_DT | 1u << HEMO_DFSPH_BINDING_CLOCK,
                                1u << HEMO_DFSPH_BINDING_POSITIONS | 1u << HEMO_DFSPH_BINDING_VELOCITIES |
                                    1u << HEMO_DFSPH_BINDING_ACCEL | 1u << HEMO_DFSPH_BINDING_PAIR_COUNT |
                                    1u << HEMO_DFSPH_BINDING_PAIR_LIST});
    dfsphCorrect_ = &cache.get({"sph/dfsph_correct", HEMO_DFSPH_CORRECT_BINDING_COUNT, sizeof(DfsphCorrectPush), kWorkgroup,
                                pairSpecialization({listWidth_}), 1u << HEMO_DFSPH_BINDING_PARAMS,
                                1u << HEMO_DFSPH_BINDING_POSITIONS | 1u << HEMO_DFSPH_BINDING_PAIR_COUNT |
                                    1u << HEMO_DFSPH_BINDING_PAIR_LIST | 1u << HEMO_DFSPH_BINDING_KAPPA});
    dfsphReduce_ = &cache.get({"sph/dfsph_reduce", HEMO_DFSPH_REDUCE_BINDING_COUNT, sizeof(DfsphReducePush), kWorkgroup,
                               {}, 0u, 0u});
    // one partial per workgroup of a prediction over every slot
    solvePartials_ = gpu::Buffer(context, dfsphPredict_->groupsFor(slots).total() * 4, gpu::MemoryUse::Device,
                                 "dfsph error partials");
    dfsphPredictSet_ = dfsphPredict_->makeSet({gpu::texelBinding(HEMO_DFSPH_BINDING_POSITIONS, &a.positions, gpu::texel::kVec4),
                                               gpu::texelBinding(HEMO_DFSPH_BINDING_VELOCITIES, &a.velocities, gpu::texel::kVec4),
                                               gpu::texelBinding(HEMO_DFSPH_BINDING_ACCEL, &accel_, gpu::texel::kVec4),
                                               {HEMO_DFSPH_BINDING_PARAMS, &paramsBuffer_},
                                               {HEMO_DFSPH_BINDING_STATE, &state_},
                                               countsAt(HEMO_DFSPH_BINDING_PAIR_COUNT, &pairCount_),
                                               listAt(HEMO_DFSPH_BINDING_PAIR_LIST, &pairList_[0]),
                                               {HEMO_DFSPH_BINDING_KAPPA, &kappa_},
                                               {HEMO_DFSPH_BINDING_VISCOUS_VEL, &viscousVel_},  // (unused: the correction's)
                                               {HEMO_DFSPH_BINDING_PARTIALS, &solvePartials_},
                                               {HEMO_DFSPH_BINDING_DT, &dtResult_},
                                               {HEMO_DFSPH_BINDING_CLOCK, &clock_}});
    dfsphCorrectSet_ = dfsphCorrect_->makeSet({gpu::texelBinding(HEMO_DFSPH_BINDING_POSITIONS, &a.positions, gpu::texel::kVec4),
                                               {HEMO_DFSPH_BINDING_VELOCITIES, &a.velocities},
                                               {HEMO_DFSPH_BINDING_VISCOUS_VEL, &viscousVel_},
                                               {HEMO_DFSPH_BINDING_ACCEL, &accel_},
                                               {HEMO_DFSPH_BINDING_PARAMS, &paramsBuffer_},
                                               {HEMO_DFSPH_BINDING_STATE, &state_},
                                               countsAt(HEMO_DFSPH_BINDING_PAIR_COUNT, &pairCount_),
                                               listAt(HEMO_DFSPH_BINDING_PAIR_LIST, &pairList_[0]),
                                               gpu::texelBinding(HEMO_DFSPH_BINDING_KAPPA, &kappa_, gpu::texel::kVec4)});
    dfsphReduceSet_ = dfsphReduce_->makeSet({{HEMO_DFSPH_REDUCE_BINDING_PARTIALS, &solvePartials_},
                                             {HEMO_DFSPH_REDUCE_BINDING_STATS, &solveStats_},
                                             {HEMO_DFSPH_REDUCE_BINDING_ARMED, &pressureGate_.armedCounts()},
                                             {HEMO_DFSPH_REDUCE_BINDING_ARGS, &pressureGate_.arguments()},
                                             {HEMO_DFSPH_REDUCE_BINDING_OPENED, &pressureGate_.openings()},
                                             {HEMO_DFSPH_REDUCE_BINDING_DEPTH, &solveDepth_}});
  }
  solveStats_.upload(std::vector<std::uint32_t>(2 * HEMO_DFSPH_STAT_COUNT, 0u));
  solveDepth_.upload(std::vector<std::uint32_t>(HEMO_DFSPH_DEPTH_COUNT, 0u));
  checkCount_.upload(std::vector<std::uint32_t>{0u});
  dtCounts_.upload(std::vector<std::uint32_t>{0u, 0u, 0u, 0u});
  checkResult_.upload(std::vector<float>{0.0f, 0.0f, 0.0f, 0.0f});
  tileGrid_.upload(std::vector<TileGrid>{tileSpec_});
  tileBoxes_.upload(std::vector<std::uint32_t>(std::size_t(tileSpec_.tiles()) * HEMO_TILE_WORDS, 0u));
  tileResult_.upload(std::vector<float>{0.0f});
  tileOccupied_.upload(std::vector<std::uint32_t>{0u, 0u});
  viscosity_.upload(std::vector<float>(viscosity_.size() / 4, 0.0f));
}

std::vector<std::uint32_t> SphSolver::pairSpecialization(std::vector<std::uint32_t> constants) const {
  // constants 1, 2, ... of the pass, then HEMO_SPEC_PERIODIC_AXES (interface/sph.h)
  constants.resize(HEMO_SPEC_PERIODIC_AXES - 1, 0u);
  constants.push_back(periodicAxes_);
  return constants;
}

float SphSolver::rebuildThreshold() const { return 0.5f * (params_.listRadius - params_.supportRadius); }

void SphSolver::attachWall(const SpringNetwork& network) {
  // (walking cells: the grid's positions at build and its cellStart, common/cell_walk.glsl)
  std::vector<const gpu::Buffer*> pages;
  for (const gpu::Buffer& page : nlist_) pages.push_back(cellWalk_ ? &grid_.cellStart() : &page);
  const gpu::Buffer* counts = cellWalk_ ? &grid_.positionsAtBuild() : &ncount_;
  const VkFormat countsFormat = cellWalk_ ? gpu::texel::kUvec4 : gpu::texel::kUint;
  const FluidBuffers fluid{&grid_.slotOfId(), &accel_,      &dtLimit_,      &paramsBuffer_, &state_,
                           counts,             countsFormat, pages,          pageSlots_,     &viscousVel_,
                           &pairPosition_,     listWidth_,   &dtPartials_,   &dtCounts_,     pairSpecialization({listWidth_}),
                           cellWalk_,          solvesPressure() ? &kappa_ : nullptr,
                           &dtResult_,         &clock_,        &viscosity_,    settings_.nonNewtonian()};
  if (network.substeps > 1 && settings_.integrator != Integrator::SymplecticEuler) {
    throw std::invalid_argument("the wall's substeps step with symplectic Euler (the scene's integrator is RK2)");
  }
  wall_ = std::make_unique<MassSpring>(*context_, *particles_, fluid, network, settings_.gravity,
                                       params_.cflAcoustic * params_.h, params_.c0);
}

void SphSolver::attachTools(const std::vector<ToolSpec>& tools) {
  const ToolBuffers buffers{&accel_,
                            &paramsBuffer_,
                            &clock_,
                            &dtCounts_,
                            wall_ ? &wall_->pointInfo() : nullptr,
                            wall_ ? wall_->pointCount() : 0u,
                            wall_ && wall_->substeps() > 1 ? &wall_->held() : nullptr,
                            wall_ ? wall_->timeStepFactor() : 0.1f,
                            wall_ ? &wall_->springs() : nullptr,
                            wall_ ? &wall_->counters() : nullptr,
                            &grid_.slotOfId(),
                            wall_ ? wall_->springCount() : 0u};
  // Psi per unit scale, c0^2 / 2h, from the scene's sound speed (under DFSPH too, as the
  // boundary repulsion's)
  const double c0 = settings_.soundSpeed;
  tools_ = std::make_unique<ToolContact>(*context_, *particles_, buffers, tools, float(c0 * c0 / (2.0 * settings_.h())),
                                         settings_.spacing, maxStepsPerBatch_);
  makeDtReduceSet();
  toolPlaceholder_ = gpu::Buffer();  // no longer bound
}

void SphSolver::makeDtReduceSet() {
  // Without tools the tools' slots hold placeholders (the uniform one the block's full size).
  if (!tools_ && !toolPlaceholder_.valid()) {
    toolPlaceholder_ = gpu::Buffer(*context_, HEMO_TOOL_DATA_VEC4S * 16, gpu::MemoryUse::Device, "tool placeholder");
  }
  const gpu::Buffer* data = tools_ ? &tools_->data() : &toolPlaceholder_;
  dtReduceSet_ = dtReduce_->makeSet(
      {gpu::texelBinding(HEMO_DTREDUCE_BINDING_PARTIALS, &dtPartials_, gpu::texel::kVec2),
       {HEMO_DTREDUCE_BINDING_COUNTS, &dtCounts_},
       {HEMO_DTREDUCE_BINDING_RESULT, &dtResult_},
       gpu::texelBinding(HEMO_DTREDUCE_BINDING_TOOL_PARTIALS, tools_ ? &tools_->dtPartials() : &dtPartials_,
                         gpu::texel::kVec2),
       {HEMO_DTREDUCE_BINDING_TOOLS, data},
       {HEMO_DTREDUCE_BINDING_CLOCK, &clock_},
       {HEMO_DTREDUCE_BINDING_TOOL_FORCES, tools_ ? &tools_->partials() : data},
       {HEMO_DTREDUCE_BINDING_TOOL_FORCE_COUNT, tools_ ? &tools_->partialCount() : data},
       {HEMO_DTREDUCE_BINDING_TOOL_LOG, tools_ ? &tools_->log() : data}});
}

const gpu::ComputePipeline& SphSolver::integratePipeline(std::uint32_t mode, std::uint32_t inflow, bool collect) {
  const gpu::ComputePipeline*& pipeline = integrate_[inflow][collect ? 3 : mode];
  if (!pipeline) {
    pipeline = &context_->pipelines().get(
        {"sph/integrate", HEMO_INTEGRATE_BINDING_COUNT, sizeof(IntegratePush), kWorkgroup,
         {continuity_, mode, inflow, collect ? 1u : 0u},
         1u << HEMO_INTEGRATE_BINDING_PARAMS | 1u << HEMO_INTEGRATE_BINDING_INFLOW | 1u << HEMO_INTEGRATE_BINDING_DT |
             1u << HEMO_INTEGRATE_BINDING_DRIFT_RANGE | 1u << HEMO_INTEGRATE_BINDING_TILE_GRID,
         1u << HEMO_INTEGRATE_BINDING_ACCEL | 1u << HEMO_INTEGRATE_BINDING_POS_AT_BUILD | 1u << HEMO_INTEGRATE_BINDING_STATE |
             1u << HEMO_INTEGRATE_BINDING_POSITIONS_IN | 1u << HEMO_INTEGRATE_BINDING_VELOCITIES_IN});
  }
  return *pipeline;
}

void SphSolver::setInflow(const Inflow& inflow) {
  const InflowParams p = makeInflowParams(inflow, settings_.restDensity, settings_.particleMass());
  if (inflow.open && !settings_.parkedSlots) {
    throw std::invalid_argument("open ends need the solver's settings to say the fluid has parked slots (SphSettings::parkedSlots)");
  }
  if (openOn_ && !inflow.open) throw std::invalid_argument("a vessel's open ends cannot be closed while it runs");
  if (openOn_ && p.endCount != openEnds_) throw std::invalid_argument("a vessel's open ends cannot change in number while it runs");
  if (inflow.open && particles_->fluidCount() >= (1u << HEMO_SPAWN_END_SHIFT)) {
    throw std::invalid_argument("open ends take at most 2^" + std::to_string(HEMO_SPAWN_END_SHIFT) + " fluid slots");
  }
  inflow_.upload(std::vector<InflowParams>{p});
  inflowOn_ = p.enabled != 0u;
  openOn_ = p.open != 0u;
  openEnds_ = p.endCount;
  if (inflowOn_) {
    for (std::uint32_t mode = 0; mode < 3; ++mode) integratePipeline(mode, inflowVariant());
    integratePipeline(HEMO_INTEGRATE_SYMPLECTIC_EULER, inflowVariant(), true);
  }
  // (the lumen's speeds and pressure next to each plane: every open end uses them)
  if (openOn_ && !openProfilePass_) {
    openProfilePass_ = &context_->pipelines().get({"sph/open_profile", HEMO_OPROFILE_BINDING_COUNT, 0, kWorkgroup, {}, 0u, 0u});
    openProfileSet_ = openProfilePass_->makeSet({{HEMO_OPROFILE_BINDING_SUMS, &openSums_},
                                                 {HEMO_OPROFILE_BINDING_PROFILE, &openProfile_}});
  }
  if (openOn_ && !spawn_) {
    const std::uint64_t n = std::max(particles_->fluidCount(), 1u);
    // (the flags of 2E + 1 segments and their total, scanned; then the ends' deficits)
    const std::uint64_t segments = 2 * std::uint64_t(openEnds_) + 1;
    spawnScan_ = gpu::Buffer(*context_, (segments * n + 1 + openEnds_) * 4, gpu::MemoryUse::Device, "open ends' refill scan");
    crossers_ = gpu::Buffer(*context_, n * 4, gpu::MemoryUse::Device, "open ends' crossers by rank");
    spawnScanner_ = std::make_unique<gpu::PrefixScan>(*context_, spawnScan_, segments * n + 1);
    spawn_ = &context_->pipelines().get({"sph/open_spawn", HEMO_SPAWN_BINDING_COUNT, 8, kWorkgroup, {},
                                         1u << HEMO_SPAWN_BINDING_INFLOW, 0u});
    const ParticleArrays& a = particles_->live();
    spawnSet_ = spawn_->makeSet({{HEMO_SPAWN_BINDING_POSITIONS, &a.positions},
                                 {HEMO_SPAWN_BINDING_VELOCITIES, &a.velocities},
                                 {HEMO_SPAWN_BINDING_NORMALS, &a.normals},
                                 {HEMO_SPAWN_BINDING_PENDING, &pending_},
                                 {HEMO_SPAWN_BINDING_SCAN, &spawnScan_},
                                 {HEMO_SPAWN_BINDING_CROSSERS, &crossers_},
                                 {HEMO_SPAWN_BINDING_INFLOW, &inflow_},
                                 {HEMO_SPAWN_BINDING_COUNTERS, &openCounters_},
                                 {HEMO_SPAWN_BINDING_STATUS, &status_}});
  }
}

void SphSolver::recordOpenRefill(gpu::CommandRecorder& rec) {
  if (!openOn_) return;
  struct SpawnPush {
    std::uint32_t n, mode;
  };
  const std::uint32_t n = particles_->fluidCount();
  rec.dispatch(*spawn_, spawnSet_, SpawnPush{n, HEMO_SPAWN_FLAGS}, spawn_->groupsFor(std::max(n, 1u)));
  rec.computeToCompute();
  spawnScanner_->record(rec, (2 * std::uint64_t(openEnds_) + 1) * n + 1);
  rec.computeToCompute();
  rec.dispatch(*spawn_, spawnSet_, SpawnPush{n, HEMO_SPAWN_SCATTER}, spawn_->groupsFor(std::max(n, 1u)));
  rec.computeToCompute();
  rec.dispatch(*spawn_, spawnSet_, SpawnPush{n, HEMO_SPAWN_COPY}, spawn_->groupsFor(std::max(n, 1u)));
  rec.computeToCompute();
}

void SphSolver::setEscapeMask(const std::vector<std::uint32_t>& words) {
  if (words.size() * 4 != escapeMask_.size()) {
    throw std::invalid_argument("open ends' escape mask: " + std::to_string(words.size()) + " words for a grid of " +
                                std::to_string(escapeMask_.size() / 4));
  }
  escapeMask_.upload(words);
}

SphSolver::OpenCounts SphSolver::readOpenCounts() const {
  const std::vector<std::uint32_t> c = openCounters_.readback<std::uint32_t>(HEMO_OPEN_COUNTER_COUNT);
  OpenCounts o;
  o.parkedOutside = c[HEMO_OPEN_COUNTER_PARKED_OUTSIDE];
  for (std::uint32_t e = 0; e < openEnds_; ++e) {
    const OpenCounts::End end{c[HEMO_OPEN_COUNTER_LEAVE(e)], c[HEMO_OPEN_COUNTER_ENTER(e)], c[HEMO_OPEN_COUNTER_PARKED(e)],
                              c[HEMO_OPEN_COUNTER_SPAWNED(e)]};
    o.ends.push_back(end);
    o.spawned += end.spawned;
    if (e == 0) {
      o.in = end.leave, o.inBack = end.enter, o.parkedStart = end.parked;
    } else {
      o.out += end.enter, o.outBack += end.leave, o.parkedEnd += end.parked;
    }
  }
  return o;
}

void SphSolver::setBackgroundPressure(float pascals) {
  if (!std::isfinite(pascals)) throw std::invalid_argument("background pressure must be finite (Pa)");
  settings_.backgroundPressure = pascals;
  params_.backgroundPressure = pascals;
  paramsBuffer_.upload(std::vector<SphParams>{params_});
}

void SphSolver::recordReset(gpu::CommandRecorder& rec) {
  if (wall_) wall_->recordReset(rec);
  rec.fill(clock_, 0);
  clockParity_ = 0;
  boundaryClockIn_ = ~0u;
  // No list yet: the active list is empty until the first build.
  rec.fill(activeArgs_, 0u);
  rec.fill(status_, 0);
  rec.fill(openCounters_, 0u);
  rec.fill(pending_, 0u);
  rec.fill(openSums_, 0u);
  rec.fill(openProfile_, 0u, 0, HEMO_OPEN_PRESSURE(0u) * 4);  // (the buffers start at rest)
  const float none = HEMO_OPEN_NO_PRESSURE;
  std::uint32_t noneBits;
  std::memcpy(&noneBits, &none, 4);
  rec.fill(openProfile_, noneBits, HEMO_OPEN_PRESSURE(0u) * 4, HEMO_OPEN_MAX_ENDS * 4);  // (no pressure measured yet)
  rec.transferToTransfer();  // the fills below overwrite some of these words
  rec.fill(status_, 0xffffffffu, HEMO_STATUS_FIRST_BAD_STEP * 4, 4);
  rec.fill(status_, 0xffffffffu, HEMO_STATUS_BAD_INPUT_ID * 4, 8);  // and BAD_FORCE_ID
  // the first step builds the list
  rec.fill(checkResult_, 0u, 0, 8);  // displacement range (0, 0): the build restarts it
  rec.fill(checkResult_, 0x7f800000u, HEMO_CHECK_RESULT_REACH * 4, 4);  // reach +inf: the gate opens
  integrateArgsValid_ = false;  // (and the next integrator collects: the reach is +inf)
  grid_.resetCounters(rec);
  rebuildGate_.recordReset(rec);
  rec.fill(solveStats_, 0u);
  rec.fill(kappa_, 0u);  // (the pressure a step past the end time keeps)
  // Density and pressure are 0 until the first step computes them (outputs before it show
  // zeros, never the allocation's leftovers)
  rec.fill(state_, 0u);
  pressureGate_.recordReset(rec);
  armPending_ = true;
}

void SphSolver::recordRebuildRequest(gpu::CommandRecorder& rec) {
  rec.computeToTransfer();  // the last step's check wrote the result
  rec.fill(checkResult_, 0u, 0, 8);  // displacement range (0, 0): the build restarts it
  rec.fill(checkResult_, 0x7f800000u, HEMO_CHECK_RESULT_REACH * 4, 4);  // reach +inf: the gate opens
  rec.transferToCompute();
  integrateArgsValid_ = false;
  armPending_ = true;
}

void SphSolver::recordNeighbours(gpu::CommandRecorder& rec, gpu::TimestampQueries* timestamps) {
  recordNeighbours(rec, movingSlots(), timestamps);
}

void SphSolver::recordNeighbours(gpu::CommandRecorder& rec, std::uint32_t sorted, gpu::TimestampQueries* timestamps) {
  const std::uint32_t n = particles_->count();
  // Past movingSlots() the slots hold rigid boundary particles in the grid order of an
  // earlier build, where they still are: the grid sorts the moving slots only.
  grid_.record(rec, n, sorted, timestamps);
  if (sorted == n) sortedUpload_ = particles_->uploads();  // every slot sorted: the grid's order
  // With clusters the fluid's lists are the clusters'; the per-particle lists are built for
  // the boundary and wall slots only (the boundary-pressure pass and the wall's reaction),
  // and not at all when the boundary slots are in clusters too.
  const std::uint32_t fluid = particles_->fluidCount();
  if (!boundaryClusterPath()) {
    const std::uint32_t listFirst = clusterPath() ? fluid : 0u;
    if (cellWalk_) {  // no list: one workgroup whose invocation 0 empties the active list
      rec.dispatch(*buildList_, buildListSets_[0], BuildPush{grid_.push(n), 0u, 0u}, buildList_->groupsFor(1u));
    } else if (listPages() == 1) {  // (at least one workgroup: its invocation 0 empties the active list)
      rec.dispatch(*buildList_, buildListSets_[0], BuildPush{grid_.push(n), listFirst, n},
                   buildList_->groupsFor(std::max(n - listFirst, 1u)));
    } else {
      forEachPage(rec, listFirst, n, [&](std::uint32_t p, std::uint32_t first, std::uint32_t end) {
        rec.dispatch(*buildList_, buildListSets_[p], BuildPush{grid_.push(n), first, end}, buildList_->groupsFor(end - first));
      });
    }
    rec.computeToCompute();
    if (timestamps) timestamps->mark(rec, "neighbour list");
  }
  if (clusterPath()) {
    const std::uint32_t clusters = clusterCount();
    // (its invocation 0 empties the boundary pass's active list)
    rec.dispatch(*buildClusters_, buildClustersSet_, ClusterBuildPush{grid_.push(n), 0u, fluid, clusterCapacity_, 0u, 0u},
                 buildClusters_->groupsFor(std::max(clusters, 1u)));
    if (boundaryClusterPath()) {
      // the boundary slots' clusters, numbered after the fluid's (their lists hold fluid only)
      rec.dispatch(*buildClusters_, buildClustersSet_, ClusterBuildPush{grid_.push(n), fluid, n, clusterCapacity_, clusters, 1u},
                   buildClusters_->groupsFor(boundaryClusterCount()));
    }
    rec.computeToCompute();
    // the pair passes' walk order, from the fluid clusters' counts
    rec.dispatch(*clusterOrder_, clusterOrderSet_, ClusterOrderPush{clusters, 0u, 0u},
                 clusterOrder_->groupsFor(std::max(clusters, 1u)));
    rec.computeToCompute();
    if (timestamps) timestamps->mark(rec, "cluster list");
  }
  // The boundary and wall particles: those with fluid in the new list to the active list,
  // the others set to a state without fluid neighbours until the next build.
  recordBoundaryRange(rec, HEMO_BPRESSURE_SORT, clockParity_);
  rec.computeToCompute();
  if (timestamps) timestamps->mark(rec, "boundary sort");
}

void SphSolver::recordBoundaryRange(gpu::CommandRecorder& rec, std::uint32_t mode, std::uint32_t clockIn) {
  const std::uint32_t n = particles_->count();
  const std::uint32_t first = nonFluidStart();
  if (boundaryClusterPath()) {
    const bool sorting = mode == HEMO_BPRESSURE_SORT;
    rec.dispatch(*boundaryClusters_, sorting ? boundaryClustersSortSet_ : boundaryClustersSet_,
                 BoundaryClusterPush{{first, n, clockIn, mode}, clusterCapacity_, clusterCount()},
                 boundaryClusters_->groupsFor(boundaryClusterCount()));
    if (sorting) {  // the active list as appended, in the walk order (sph/cluster_order.comp)
      rec.computeToCompute();
      rec.dispatch(*clusterOrder_, boundaryOrderSet_, ClusterOrderPush{boundaryClusterCount(), 1u, clusterCount()},
                   clusterOrder_->groupsFor(boundaryClusterCount()));
    }
    return;
  }
  forEachPage(rec, first, n, [&](std::uint32_t p, std::uint32_t lo, std::uint32_t hi) {
    rec.dispatch(*boundaryPressure_, boundarySets_[p], BoundaryPush{lo, hi, clockIn, mode}, boundaryPressure_->groupsFor(hi - lo));
  });
}

void SphSolver::recordBoundaryRest(gpu::CommandRecorder& rec) {
  if (boundaryClockIn_ == ~0u) return;
  rec.computeToCompute();
  recordBoundaryRange(rec, HEMO_BPRESSURE_REST, boundaryClockIn_);
  rec.computeToCompute();
}

void SphSolver::recordDensity(gpu::CommandRecorder& rec, gpu::TimestampQueries* timestamps) {
  recordDensityOver(rec, particles_->count(), timestamps);
}

void SphSolver::recordDensityOver(gpu::CommandRecorder& rec, std::uint32_t fluidSlots,
                                  gpu::TimestampQueries* timestamps) {
  const std::uint32_t n = particles_->count();
  if (clusterPath()) {
    const std::uint32_t fluid = particles_->fluidCount();
    const std::uint32_t clusters = clusterCount();
    rec.dispatch(*densityClusters_, densityClustersSet_, ClusterPush{fluid, clusterCapacity_, clockParity_},
                 densityClusters_->groupsFor(std::max(clusters, 1u)));
  } else {
    forEachPage(rec, 0, fluidSlots, [&](std::uint32_t p, std::uint32_t first, std::uint32_t end) {
      rec.dispatch(*density_, densitySets_[p], DensityPush{end, clockParity_, first}, density_->groupsFor(end - first));
    });
  }
  rec.computeToCompute();
  if (timestamps) timestamps->mark(rec, "density");
  // DFSPH: the velocities at the new positions lose their compressive divergence before the
  // boundary pass extrapolates them to the wall (interface/sph.h, "The pressure solver").
  if (solvesPressure()) recordPressureSolveOver(rec, fluidSlots, 3.0e38f, timestamps, HEMO_DFSPH_MODE_DIVERGENCE);
  // Over the active list of the last build (recordNeighbours), as many workgroups as it counted.
  if (boundaryClusterPath()) {
    rec.dispatchIndirect(*boundaryClusters_, boundaryClustersSet_,
                         BoundaryClusterPush{{nonFluidStart(), n, clockParity_, HEMO_BPRESSURE_ACTIVE}, clusterCapacity_, clusterCount()},
                         activeArgs_, 0);
  } else {
    // each page's active list, as its sort appended it
    forEachPage(rec, nonFluidStart(), n, [&](std::uint32_t p, std::uint32_t, std::uint32_t) {
      rec.dispatchIndirect(*boundaryPressure_, boundarySets_[p], BoundaryPush{0, n, clockParity_, HEMO_BPRESSURE_ACTIVE},
                           activeArgs_, kActiveArgsStride * p);
    });
  }
  boundaryClockIn_ = clockParity_;
  rec.computeToCompute();
  if (timestamps) timestamps->mark(rec, "boundary pressure");
}

void SphSolver::recordForces(gpu::CommandRecorder& rec) { recordForcesOver(rec, particles_->count()); }

void SphSolver::recordForcesOver(gpu::CommandRecorder& rec, std::uint32_t fluidSlots,
                                 gpu::TimestampQueries* timestamps) {
  const std::uint32_t n = particles_->count();
  if (settings_.sps || settings_.nonNewtonian()) {  // only scenes that ask for turbulence or blood's thinning pay for it
    forEachPage(rec, 0, fluidSlots, [&](std::uint32_t p, std::uint32_t lo, std::uint32_t hi) {
      rec.dispatch(*spsStress_, spsSets_[p], SpsPush{hi, lo}, spsStress_->groupsFor(hi - lo));
    });
    rec.computeToCompute();
  }
  // The time step's reduction: the SIMD groups of this pass and, with a wall, of the wall
  // stage store partials, and one workgroup reduces them (common/dt_fold.glsl).
  const std::uint32_t first = nonFluidStart();
  const bool wallRuns = wall_ && wall_->workgroups(first, n) > 0;
  const auto wallBase = static_cast<std::uint32_t>(partialsPerPass(*particles_));
  gpu::Groups groups;
  if (clusterPath()) {
    const std::uint32_t fluid = particles_->fluidCount();
    const std::uint32_t clusters = clusterCount();
    groups = forcesClusters_->groupsFor(std::max(clusters + (fluidSlots - std::min(fluid, fluidSlots)), 1u));
    rec.dispatch(*forcesClusters_, forcesClustersSet_, ClusterPush{fluid, clusterCapacity_, fluidSlots}, groups);
  } else {
    groups = forces_->groupsFor(fluidSlots);
    // Pages start at multiples of the workgroup size: each page's time-step partials follow
    // the previous page's, and the last page writes their count (common/dt_fold.glsl).
    static_assert(kWorkgroup <= 1024, "pages of at least 1024 slots start on workgroup boundaries");
    const std::uint32_t lastPage = fluidSlots > 0 ? (fluidSlots - 1) / pageSlots_ : 0u;
    forEachPage(rec, 0, fluidSlots, [&](std::uint32_t p, std::uint32_t lo, std::uint32_t hi) {
      rec.dispatch(*forces_, forcesSets_[p], ForcesPush{hi, lo, p == lastPage ? 1u : 0u}, forces_->groupsFor(hi - lo));
    });
  }
  rec.computeToCompute();
  if (timestamps) timestamps->mark(rec, "forces");
  if (tools_ && tools_->cuts()) {  // the blades cut before the springs pull
    tools_->recordCut(rec, clockParity_);
    rec.computeToCompute();
  }
  if (wall_) {
    wall_->record(rec, first, n, wallBase);  // the wall, solved after the fluid in every force evaluation
    if (timestamps) timestamps->mark(rec, "wall");
  }
  if (tools_) {  // the tools press on what the fluid's forces and the springs have moved
    tools_->record(rec, fluidSlots, clockParity_, wall_ && wall_->substeps() > 1);
    rec.computeToCompute();
    if (timestamps) timestamps->mark(rec, "tools");
  }
  const std::uint32_t passes = (groups.total() > 0 ? 1u : 0u) | (wallRuns ? 2u : 0u) | (tools_ ? 4u : 0u);
  rec.dispatch(*dtReduce_, dtReduceSet_,
               DtReducePush{wallBase, passes, tools_ ? tools_->count() : 0u, tools_ ? tools_->partialStride() : 0u,
                            clockParity_, toolLogIndex_},
               dtReduce_->groupsFor(1u));
  rec.computeToCompute();
}

void SphSolver::recordIntegrate(gpu::CommandRecorder& rec, std::uint32_t step, std::uint32_t logIndex, float endTime) {
  recordIntegrateMode(rec, step, logIndex, endTime, HEMO_INTEGRATE_SYMPLECTIC_EULER, particles_->count());
}

void SphSolver::recordIntegrateMode(gpu::CommandRecorder& rec, std::uint32_t step, std::uint32_t logIndex,
                                    float endTime, std::uint32_t mode, std::uint32_t moving,
                                    gpu::TimestampQueries* timestamps) {
  auto mark = [&](const char* stage) {
    if (timestamps) timestamps->mark(rec, stage);
  };
  if (logIndex >= maxStepsPerBatch_) {
    throw std::out_of_range("step log index " + std::to_string(logIndex) + " exceeds the batch capacity " +
                            std::to_string(maxStepsPerBatch_));
  }
  const std::uint32_t n = particles_->count();
  // The second stage reuses the step's dt; slots past `moving` (rigid) have no limit.
  // At least one workgroup: invocation 0 advances the clock even with no particles, and a
  // full stage's partials of the rebuild test must not be empty.
  const bool wallAdvanced = wall_ && wall_->substeps() > 1 && mode == HEMO_INTEGRATE_SYMPLECTIC_EULER;
  if (wallAdvanced) {
    wall_->recordSubsteps(rec, nonFluidStart(), n, clockParity_, endTime);
    mark("wall substeps");
  }
  const IntegratePush push{moving, step, logIndex, endTime, clockParity_, rebuildThreshold(), wallAdvanced ? 1u : 0u};
  const std::uint32_t inflow = inflowVariant();
  const gpu::ComputePipeline& integrate = *integrate_[inflow][mode];
  const gpu::Groups groups = integrate.groupsFor(std::max(moving, 1u));
  if (mode != HEMO_INTEGRATE_SYMPLECTIC_EULER) {
    rec.dispatch(integrate, integrateSet_, push, groups);
  } else if (integrateArgsValid_ && integrateArgsGroups_.x == groups.x && integrateArgsGroups_.y == groups.y) {
    // the variant the last step's decision chose; the other gets no workgroups
    rec.dispatchIndirect(*integrate_[inflow][3], integrateSet_, push, integrateArgs_, 0);
    // Only one of the two gets workgroups, but the GPU decides which: the barrier orders the
    // pair whatever the counts (the second reads what the first writes when both run).
    rec.computeToCompute();
    rec.dispatchIndirect(integrate, integrateSet_, push, integrateArgs_, 16);
  } else {
    // after a reset of the rebuild test (the reach is +inf, so the test collects), or with
    // other workgroups than the decision wrote: collecting is always a valid choice
    rec.dispatch(*integrate_[inflow][3], integrateSet_, push, groups);
  }
  if (mode != HEMO_INTEGRATE_RK2_HALF) {
    // the rebuild test's reduction (with the tile test after symplectic Euler) decides and
    // arms the gate (interface/sph.h)
    rec.computeToCompute();
    mark("integrate");
    const std::uint32_t tiles = mode == HEMO_INTEGRATE_SYMPLECTIC_EULER ? 1u : 0u;
    rec.dispatch(*rebuildDecide_[tiles], rebuildDecideSet_,
                 DecidePush{rebuildThreshold(), rebuildGate_.slots(), moving < n ? 1u : 0u, groups.x, groups.y},
                 rebuildDecide_[tiles]->groupsFor(1u));
    if (openOn_) {  // (the open ends' profiles for the next step, beside the decision)
      rec.dispatch(*openProfilePass_, openProfileSet_, nullptr, 0, openProfilePass_->groupsFor(kOpenProfile));
    }
    if (tiles != 0u) {
      integrateArgsValid_ = true;
      integrateArgsGroups_ = groups;
    }
  }
  if (mode != HEMO_INTEGRATE_RK2_HALF) {
    clockParity_ ^= 1u;  // the half stage leaves the clock alone
    rec.computeToCompute();  // the gate's arguments; the test's result for the next step
    mark("rebuild test");
  } else {
    rec.computeToCompute();
  }
}

void SphSolver::recordPressureSolve(gpu::CommandRecorder& rec, float endTime, gpu::TimestampQueries* timestamps) {
  recordPressureSolveOver(rec, particles_->count(), endTime, timestamps, HEMO_DFSPH_MODE_DENSITY);
}

void SphSolver::recordPressureSolveOver(gpu::CommandRecorder& rec, std::uint32_t fluidSlots, float endTime,
                                        gpu::TimestampQueries* timestamps, std::uint32_t mode) {
  if (!solvesPressure()) throw std::logic_error("recordPressureSolve: the scene's solver is WCSPH");
  const gpu::Groups groups = dfsphPredict_->groupsFor(std::max(fluidSlots, 1u));
  const auto partials = static_cast<std::uint32_t>(groups.total());
  auto predict = [&](std::uint32_t iteration) { return DfsphPredictPush{fluidSlots, clockParity_, endTime, iteration, mode}; };
  const std::uint32_t statBase = mode == HEMO_DFSPH_MODE_DIVERGENCE ? HEMO_DFSPH_STAT_COUNT : 0u;
  const std::uint32_t cap = settings_.solverMaxIterations;
  const std::uint32_t recorded = std::min(recordedIterations_, cap);
  auto reduce = [&](std::uint32_t iteration) {
    rec.dispatch(*dfsphReduce_, dfsphReduceSet_,
                 DfsphReducePush{partials, particles_->fluidCount(), iteration, cap, settings_.solverTolerance,
                                 pressureGate_.slots(), statBase, recorded,
                                 mode == HEMO_DFSPH_MODE_DIVERGENCE ? HEMO_DFSPH_MIN_DIVERGENCE_CORRECTIONS
                                                                    : HEMO_DFSPH_MIN_DENSITY_CORRECTIONS},
                 dfsphReduce_->groupsFor(1u));
    rec.computeToCompute();  // the stats; the gate's arguments before the region's indirect reads
  };
  // (the force pass's barrier has ordered the accelerations and the dt reduction before this)
  rec.dispatch(*dfsphPredict_, dfsphPredictSet_, predict(0), groups);
  rec.computeToCompute();
  reduce(0);
  for (std::uint32_t k = 1; k <= recorded; ++k) {
    rec.beginGate(pressureGate_, mode == HEMO_DFSPH_MODE_DIVERGENCE ? 1u : 0u);
    rec.dispatch(*dfsphCorrect_, dfsphCorrectSet_, DfsphCorrectPush{fluidSlots, mode},
                 dfsphCorrect_->groupsFor(std::max(fluidSlots, 1u)));
    rec.computeToCompute();
    rec.dispatch(*dfsphPredict_, dfsphPredictSet_, predict(k), groups);
    rec.endGate();
    rec.computeToCompute();
    reduce(k);
  }
  if (timestamps) timestamps->mark(rec, mode == HEMO_DFSPH_MODE_DIVERGENCE ? "divergence solve" : "pressure solve");
  if (wall_ && mode == HEMO_DFSPH_MODE_DENSITY) {
    // the wall's share: the reaction of both solves' pressure on the fluid next to it
    wall_->recordPressureReaction(rec, nonFluidStart(), particles_->count());
    if (timestamps) timestamps->mark(rec, "wall pressure reaction");
  }
}

void SphSolver::setRecordedIterations(std::uint32_t regions) {
  recordedIterations_ = std::clamp(regions, 1u, std::max(settings_.solverMaxIterations, 1u));
}

void SphSolver::recordSolveDepthReset(gpu::CommandRecorder& rec) {
  rec.fill(solveDepth_, 0u);
  rec.transferToCompute();
}

SphSolver::SolveDepth SphSolver::readSolveDepth() const {
  const auto w = solveDepth_.readback<std::uint32_t>(HEMO_DFSPH_DEPTH_COUNT);
  return SolveDepth{w[HEMO_DFSPH_DEPTH_MAX], w[HEMO_DFSPH_DEPTH_DEEPER]};
}

PressureSolveStats SphSolver::readPressureSolveStats(bool divergence) const {
  const auto all = solveStats_.readback<std::uint32_t>(2 * HEMO_DFSPH_STAT_COUNT);
  const std::uint32_t* w = all.data() + (divergence ? HEMO_DFSPH_STAT_COUNT : 0);
  auto asFloat = [](std::uint32_t bits) {
    float f;
    std::memcpy(&f, &bits, 4);
    return f;
  };
  PressureSolveStats s;
  s.lastIterations = w[HEMO_DFSPH_STAT_ITERATIONS];
  s.lastError = asFloat(w[HEMO_DFSPH_STAT_ERROR]);
  s.capHits = w[HEMO_DFSPH_STAT_CAP_HITS];
  s.solves = w[HEMO_DFSPH_STAT_SOLVES];
  s.totalIterations = w[HEMO_DFSPH_STAT_TOTAL];
  s.maxIterations = w[HEMO_DFSPH_STAT_MAX];
  s.worstError = asFloat(w[HEMO_DFSPH_STAT_WORST_ERROR]);
  return s;
}

bool SphSolver::clusterPath() const { return clusters_ && inGridOrder(); }

std::uint32_t SphSolver::boundaryClusterCount() const {
  return (particles_->count() - particles_->fluidCount() + HEMO_CLUSTER_SIZE - 1) / HEMO_CLUSTER_SIZE;
}

bool SphSolver::boundaryClusterPath() const {
  return clusterPath() && particles_->wallCount() == 0 && particles_->count() > particles_->fluidCount();
}

std::uint32_t SphSolver::clusterCount() const {
  return (particles_->fluidCount() + HEMO_CLUSTER_SIZE - 1) / HEMO_CLUSTER_SIZE;
}

bool SphSolver::inGridOrder() const {
  // A step that rebuilt the grid after the last upload has sorted the slots: the fluid's
  // first (the grid's part 0), then boundary and wall particles. Kinds never change.
  return sortedUpload_ == particles_->uploads();
}

std::uint32_t SphSolver::nonFluidStart() const {
  // The passes over boundary and wall particles start past the fluid's slots. Dispatched over
  // all slots, their work sat in the last workgroups, and lavapipe hands each thread one
  // contiguous share of a dispatch: in Table 1's tubes one thread of six ran the whole wall
  // stage (hemo-bench table1 on lavapipe).
  return inGridOrder() ? particles_->fluidCount() : 0u;
}

std::uint32_t SphSolver::movingSlots() const {
  // In the grid's order (fluid first) with no wall particles, the slots past the fluid hold
  // only rigid boundary particles, which never move: the integrator and the rebuild check
  // leave them out (the dam break: 10,296 of 19,896 slots).
  return inGridOrder() && particles_->wallCount() == 0 ? particles_->fluidCount() : particles_->count();
}

void SphSolver::recordStep(gpu::CommandRecorder& rec, std::uint32_t step, std::uint32_t logIndex, float endTime,
                           gpu::TimestampQueries* timestamps) {
  auto mark = [&](const char* stage) {
    if (timestamps) timestamps->mark(rec, stage);
  };
  if (tileUpload_ != particles_->uploads()) {
    // New particles: mark the tiles of the rigid boundary particles (they never move).
    rec.computeToTransfer();
    rec.fill(tileBoxes_, 0u);
    rec.fill(tileOccupied_, 0u, 0, 8);
    rec.transferToCompute();
    const std::uint32_t n = particles_->count();
    rec.dispatch(*tileStatic_, tileStaticSet_, CountPush{n}, tileStatic_->groupsFor(std::max(n, 1u)));
    rec.computeToCompute();
    tileUpload_ = particles_->uploads();
  }
  // Rebuild the grid and the list only when some particle may have crossed the list's skin.
  // The slots to sort, as the last build left them (the first build after an upload sorts
  // them all).
  const std::uint32_t sorted = movingSlots();
  toolLogIndex_ = logIndex;
  if (armPending_) {  // after a reset or a rebuild request; else the last step's check armed it
    rebuildGate_.recordArm(rec, HEMO_CHECK_RESULT_REACH, rebuildThreshold());
    armPending_ = false;
    sortedUpload_ = particles_->uploads();  // this step rebuilds: the slots are in grid order
  }
  // (two shapes of the region: every slot sorted, or the moving ones only)
  rec.beginGate(rebuildGate_, sorted == particles_->count() ? 0u : 1u);
  recordOpenRefill(rec);  // (open ends: the crossers' images join the grid's build)
  recordNeighbours(rec, sorted, timestamps);
  rec.endGate();
  // Past movingSlots() only rigid boundary particles, for which the density and force passes
  // do nothing (no density of their own; acceleration 0 and no time-step limit, which nobody
  // reads for them: the integrator and the dt reduction leave those slots out too).
  const std::uint32_t moving = movingSlots();
  recordDensityOver(rec, moving, timestamps);
  recordForcesOver(rec, moving, timestamps);
  if (solvesPressure()) recordPressureSolveOver(rec, moving, endTime, timestamps, HEMO_DFSPH_MODE_DENSITY);
  if (settings_.integrator == Integrator::Rk2Midpoint) {
    recordIntegrateMode(rec, step, logIndex, endTime, HEMO_INTEGRATE_RK2_HALF, moving);
    recordDensityOver(rec, moving);
    recordForcesOver(rec, moving);
    recordIntegrateMode(rec, step, logIndex, endTime, HEMO_INTEGRATE_RK2_FULL, moving);
    mark("rk2 midpoint stage + integrate");
  } else {
    recordIntegrateMode(rec, step, logIndex, endTime, HEMO_INTEGRATE_SYMPLECTIC_EULER, moving, timestamps);
  }
}

std::uint32_t SphSolver::readRebuilds() const {
  // The last step's check counts the opening it decides on; that rebuild belongs to the next
  // step, which has not run yet (unless a reset or request has re-armed the gate since).
  const std::uint32_t opened = rebuildGate_.readOpened();
  return opened - (!armPending_ && opened > 0 && rebuildGate_.readIsOpen() ? 1u : 0u);
}

SphStatus SphSolver::statusFrom(const std::uint32_t* s) {
  return SphStatus{s[HEMO_STATUS_FIRST_BAD_STEP], s[HEMO_STATUS_NONFINITE],   s[HEMO_STATUS_NEIGHBOUR_OVERFLOW],
                   s[HEMO_STATUS_MAX_NEIGHBOURS],  s[HEMO_STATUS_BAD_INPUT_ID], s[HEMO_STATUS_BAD_FORCE_ID],
                   s[HEMO_STATUS_OPEN_SHORTFALL]};
}

SphStatus SphSolver::readStatus() const { return statusFrom(status_.readback<std::uint32_t>(HEMO_STATUS_COUNT).data()); }

namespace {
struct RawClock {  // common/clock.glsl
  float time, compensation, lastDt;
  std::uint32_t steps;
};
static_assert(sizeof(RawClock) == 16);
}  // namespace

SphClock SphSolver::clockFrom(const void* records, std::uint32_t parity) {
  RawClock r;
  std::memcpy(&r, static_cast<const char*>(records) + sizeof(RawClock) * (parity & 1u), sizeof r);
  return SphClock{double(r.time) - double(r.compensation), r.lastDt, r.steps};
}

SphClock SphSolver::readClock() const { return clockFrom(clock_.readback<RawClock>(2).data()); }

void SphSolver::checkpointBuffers(std::vector<gpu::Buffer*>& out) {
  particles_->checkpointBuffers(out);
  grid_.checkpointBuffers(out);
  rebuildGate_.checkpointBuffers(out);
  out.insert(out.end(), {&paramsBuffer_, &state_, &accel_, &dtLimit_, &ncount_, &pairCount_, &viscousVel_});
  for (auto* pages : {&nlist_, &pairList_}) {
    for (gpu::Buffer& b : *pages) out.push_back(&b);
  }
  out.insert(out.end(), {&ccount_, &clist_, &corder_, &pairPosition_, &activeSlots_, &activeArgs_, &activeAppended_,
                         &integrateArgs_, &clock_, &status_, &log_, &inflow_, &savedPos_, &savedVel_, &stepDt_, &tauA_,
                         &tauB_, &viscosity_, &dtPartials_, &dtCounts_, &dtResult_, &checkPartials_, &checkCount_, &checkResult_,
                         &tileGrid_, &tileBoxes_, &tileResult_, &tileOccupied_, &kappa_, &solvePartials_, &solveStats_,
                         &openCounters_, &pending_, &openSums_, &openProfile_});
  pressureGate_.checkpointBuffers(out);
  if (wall_) wall_->checkpointBuffers(out);
  if (tools_) tools_->checkpointBuffers(out);
}

namespace {
enum HostWord : std::uint32_t {
  kClockParity,
  kBoundaryClockIn,
  kIntegrateArgsValid,
  kIntegrateGroupsX,
  kIntegrateGroupsY,
  kArmPending,
  kInGridOrder,   // the last whole build sorted the slots of this upload
  kTilesMarked,   // the rigid boundary's tiles are marked for this upload
  kHostWords
};
}  // namespace

std::vector<std::uint32_t> SphSolver::hostState() const {
  std::vector<std::uint32_t> s(kHostWords);
  s[kClockParity] = clockParity_;
  s[kBoundaryClockIn] = boundaryClockIn_;
  s[kIntegrateArgsValid] = integrateArgsValid_ ? 1u : 0u;
  s[kIntegrateGroupsX] = integrateArgsGroups_.x;
  s[kIntegrateGroupsY] = integrateArgsGroups_.y;
  s[kArmPending] = armPending_ ? 1u : 0u;
  s[kInGridOrder] = inGridOrder() ? 1u : 0u;
  s[kTilesMarked] = tileUpload_ == particles_->uploads() ? 1u : 0u;
  return s;
}

void SphSolver::restoreHostState(const std::vector<std::uint32_t>& s) {
  if (s.size() != kHostWords) {
    throw std::invalid_argument("solver state of " + std::to_string(s.size()) + " words, expected " +
                                std::to_string(kHostWords));
  }
  clockParity_ = s[kClockParity] & 1u;
  boundaryClockIn_ = s[kBoundaryClockIn] == ~0u ? ~0u : s[kBoundaryClockIn] & 1u;
  integrateArgsValid_ = s[kIntegrateArgsValid] != 0;
  integrateArgsGroups_ = gpu::Groups{s[kIntegrateGroupsX], s[kIntegrateGroupsY]};
  armPending_ = s[kArmPending] != 0;
  sortedUpload_ = s[kInGridOrder] != 0 ? particles_->uploads() : ~std::uint64_t(0);
  tileUpload_ = s[kTilesMarked] != 0 ? particles_->uploads() : ~std::uint64_t(0);
}

}  // namespace hemo::sim
