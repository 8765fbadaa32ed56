#pragma once
// Weakly compressible SPH on the GPU: one step is
//   gate ...... armed on the GPU by the previous step's rebuild check: is the neighbour list
//               still valid (no particle has moved more than half its skin since it was built)?
//   neighbours  only when not: grid (hash, counting sort, reorder), neighbour list
//   density ... summation density (fluid + boundary) from the list, Tait pressure
//   boundary .. boundary-particle pressure extrapolated from the fluid (Adami et al. 2012)
//   forces .... pressure, laminar viscosity, boundary repulsion, gravity; dt limit per particle
//   dt ........ min reduction of the limits (stays on the GPU)
//   integrate . symplectic Euler with that dt; clock, step log and status on the GPU; each
//               particle's reach since the list build
//   check ..... reduces the reaches and arms the next step's gate, in one dispatch
// Sources: Monaghan (1994) for WCSPH and the Tait equation, Mueller et al. (2003) and
// Crespo et al. (2015) for the symmetric pressure force, Morris et al. (1997) for laminar viscosity, Wendland (1995)
// for the kernel; docs/physics.md.
#include "hemo/gpu/gate.hpp"
#include "hemo/gpu/primitives.hpp"
#include "hemo/sim/inflow.hpp"
#include "hemo/sim/list_pages.hpp"
#include "hemo/sim/neighbour_grid.hpp"
#include "hemo/sim/particles.hpp"
#include "hemo/sim/tools.hpp"
#include "hemo/sim/wall.hpp"

#include <glm/vec3.hpp>
#include <glm/vector_relational.hpp>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace hemo::sim {

enum class ParticleKind : std::uint32_t { Fluid = 0, Boundary = 1 };

// Time integration: symplectic Euler (one force evaluation per step) or the second-order
// Runge-Kutta midpoint rule (two; the reference scheme).
enum class Integrator { SymplecticEuler, Rk2Midpoint };

// How the fluid's density is found (docs/physics.md).
enum class DensityMethod { Summation, Continuity };

// Memory layout of the neighbour list (interface/sph.h, listStride). Auto: clusters where they
// apply and contiguous lists otherwise on CPU devices (lavapipe), interleaved on GPUs.
// Clusters: the fluid walks one list per cluster of HEMO_CLUSTER_SIZE consecutive slots
// (interface/sph.h), the other particles contiguous lists; they apply to summation density
// with Newtonian blood and without the SPS term, else the solver uses contiguous lists. Results do
// not depend on the layout beyond the order of the sums.
enum class ListLayout { Auto, Interleaved, Contiguous, Clusters };

// How the pair passes find a particle's neighbours (docs/architecture.md, "Neighbours").
// List: a neighbour list built with the grid and reused while the skin holds, and the
// interacting pairs the density pass keeps from it (2 x 4 bytes x neighbourCapacity per
// particle). Cells: no list; each pass walks the grid cells around the particle's position
// at the last build (common/cell_walk.glsl): every pass pays for the candidates, and nothing
// per particle but the grid, so scenes several times larger fit the device; the sums are bit
// for bit those of the list. Auto: the list when the device's memory holds it with the
// solver's other buffers, else cells.
enum class NeighbourSearch { Auto, List, Cells };

// How the fluid's pressure is found (docs/physics.md, "The pressure solver"): the Tait
// equation of state of weakly compressible SPH, whose sound speed limits the step to
// C_a h / (c0 + |v|); or DFSPH's constant-density solve (Bender & Koschier 2015, 2017), which
// iterates each step until the fluid's mean compression is within a tolerance, so the step is
// limited by the flow's speed alone (C_a h / |v|). DFSPH runs with summation density,
// symplectic Euler, the neighbour list in one buffer (not in clusters), and without a vessel.
enum class PressureSolver { Wcsph, Dfsph };

// Blood's viscosity (docs/physics.md, "Non-Newtonian blood"): Newtonian (one mu), or the
// Carreau-Yasuda law, each fluid particle's viscosity from its own shear rate
// (interface/sph.h, "Viscosity").
enum class Rheology { Newtonian, CarreauYasuda };
// mu(g) = muInf + (mu0 - muInf) (1 + (lambda g)^a)^((n - 1) / a) at shear rate g (1/s). The
// defaults are the fit to whole blood of Cho & Kensey (1991) (a = 2, the Carreau law).
struct CarreauYasuda {
  float mu0 = 0.056f;      // zero-shear viscosity (Pa s)
  float muInf = 0.00345f;  // infinite-shear viscosity (Pa s)
  float lambda = 3.313f;   // relaxation time (s)
  float n = 0.3568f;       // power-law index (shear thinning: n <= 1)
  float a = 2.0f;          // Yasuda exponent
  double at(double shearRate) const;  // mu (Pa s)
};

// Physical and numerical settings (SI units).
struct SphSettings {
  float spacing = 0.0f;             // initial particle spacing dp (m)
  float smoothingRatio = 1.3f;      // h / dp
  float restDensity = 1000.0f;      // rho0 (kg/m^3)
  float viscosity = 1.0e-3f;        // dynamic viscosity mu (Pa s) of Newtonian blood
  Rheology rheology = Rheology::Newtonian;
  CarreauYasuda carreau;            // the law's parameters (Rheology::CarreauYasuda)
  float soundSpeed = 0.0f;          // c0 (m/s)
  glm::vec3 gravity{0.0f, 0.0f, -9.81f};  // m/s^2
  glm::vec3 bodyForce{0.0f};        // extra uniform acceleration (m/s^2)
  float repulsionScale = 0.01f;     // Psi = scale * c0^2 / (2h)
  float repulsionCutoffRatio = 0.5f;  // D = ratio * dp
  float cflAcoustic = 0.3f;
  float cflForce = 0.25f;
  float maxTimeStep = 1.0e-3f;      // s
  bool clampNegativePressure = true;
  std::uint32_t neighbourCapacity = 128;
  float listSkin = 0.1f;            // neighbour-list radius = 2h (1 + skin)
  ListLayout listLayout = ListLayout::Auto;
  NeighbourSearch neighbourSearch = NeighbourSearch::Auto;
  float dampingRate = 0.0f;         // settling phase: v <- v / (1 + rate dt) (1/s) ...
  float dampingUntil = 0.0f;        // ... while t < this (s)
  Integrator integrator = Integrator::SymplecticEuler;
  bool sps = false;                 // sub-particle-scale turbulence (Dalrymple & Rogers 2006)
  float smagorinsky = 0.12f;        // C_s
  float blinn = 0.0066f;            // C_I
  glm::bvec3 periodic{false};       // axes on which the domain [min, max) is periodic
  float backgroundPressure = 0.0f;  // p_bg (Pa) added to the Tait pressure: a vessel's lumen
                                    // (transmural) pressure; 0 for free surfaces
  float backgroundPressureRamp = 0.0f;  // s: p_bg rises linearly from 0 over this time (0: at once)
  // Summation density (the default), or density carried by each particle and advanced by the
  // continuity equation with the density-diffusion term of delta-SPH (docs/physics.md).
  DensityMethod densityMethod = DensityMethod::Summation;
  float deltaSph = 0.1f;            // delta of the diffusion term (continuity only)
  PressureSolver pressureSolver = PressureSolver::Wcsph;
  // DFSPH: the mean residual / rho0 each solve iterates to (see interface/sph.h)
  float solverTolerance = 1.0e-3f;
  std::uint32_t solverMaxIterations = 50;  // DFSPH: the cap on each solve's corrections per step
  // DFSPH: the density solve holds the compression the Tait law linearised at rho0 gives its
  // pressure (compliance 1 / c0^2), so it models WCSPH's fluid; false: incompressible
  // (interface/sph.h, "The pressure solver").
  bool solverCompressible = true;
  // The fluid has parked slots (open vessel ends, hemo/sim/inflow.hpp): the solver then walks
  // a per-particle list (the cluster and cell-walk passes would meet the parked slots, which
  // all lie at one point) under WCSPH.
  bool parkedSlots = false;

  float h() const { return smoothingRatio * spacing; }
  bool nonNewtonian() const { return rheology != Rheology::Newtonian; }
  // The largest viscosity the fluid can have (Pa s), which bounds the viscous time step: mu0
  // for shear-thinning blood.
  double maxViscosity() const;
  float supportRadius() const { return 2.0f * h(); }
  float listRadius() const { return supportRadius() * (1.0f + listSkin); }
  // Mass per particle such that summation density on the initial cubic lattice equals rho0
  // exactly: m = rho0 / sum_j W(|x_j|) (the kernel sum is 1/dp^3 only to within ~0.2% at
  // h/dp = 1.3, which would otherwise add a uniform 7 B 0.002 to the pressure).
  float particleMass() const;
  // The laminar (Morris) viscous term on that lattice gives the Laplacian of a velocity field
  // times this factor (0.96 at h/dp = 1.3: the eta^2 regulariser and the kernel's discrete
  // second moment); the solver divides the viscosity by it, as the mass is calibrated, so the
  // fluid has the viscosity the scene asks for (measured with plane Poiseuille flow).
  double viscousLatticeFactor() const;
  // DFSPH: sum_j |m gradW_ij|^2 over a particle's neighbours on that lattice (kg^2 m^-8), the
  // denominator of its stiffness in the bulk at rest (interface/sph.h, solveFloor).
  double stiffnessDenominatorAtRest() const;
  // Throws std::invalid_argument naming the offending setting.
  void validate() const;
};

// Mirror of the GLSL SphParams block (interface/sph.h).
struct SphParams {
  float gravity[4];
  float h, supportRadius, listRadius, kernelNorm;
  float rho0, taitB, mu, etaSq;
  float psi, repulsionCutoff, wallSpacing, cflAcoustic;
  float cflForce, dtViscous, dtMax, c0;
  std::uint32_t clampNegativePressure, neighbourCapacity;
  float dampingRate, dampingUntil;
  std::uint32_t spsEnabled;
  float spsSmagorinsky, spsBlinn;
  std::uint32_t listStride;  // set by the solver: entry k of particle i's list is at
                             // i * listParticleStride + k * listStride (interface/sph.h)
  float origin[4], period[4], invPeriod[4];  // set by the solver from its grid
  float backgroundPressure, backgroundRamp;
  std::uint32_t listParticleStride;
  float deltaSph;  // delta of the continuity density's diffusion term (0 with summation density)
  float gravityOnly[4];  // gravity without the body force (m/s^2): the diffusion term's hydrostatic part
  std::uint32_t listPageMask;  // set by the solver: slot i's index in its page of the list is i & mask
  std::uint32_t pressureSolver;  // 0: Tait (WCSPH), 1: DFSPH's solve (interface/sph.h)
  float solveFloor;  // DFSPH: the least denominator of the stiffness, kg^2 m^-8 (interface/sph.h)
  float rheologyExponent;  // non-Newtonian blood: (n - 1) / a (interface/sph.h, "Viscosity")
  // set by the solver: its neighbour grid (NeighbourGrid::Push, n unused), for the cell walks
  float gridOrigin[4], gridInvCell[4];
  std::uint32_t gridDims[4], gridPeriodic[4];
  // non-Newtonian blood: (mu_inf, mu_0 - mu_inf (Pa s, over the lattice factor), lambda (s), a);
  // zeros for Newtonian blood
  float carreau[4];
  float solveCompliance;  // DFSPH: the density solve's compliance 1 / c0^2 (s^2 m^-2), 0: incompressible
  float solvePad[3];
};
static_assert(sizeof(SphParams) == 304);

SphParams makeParams(const SphSettings& s);

// The rebuild test's tiles (common/tiles.glsl, the uniform block's layout): a regular grid over
// the domain of tiles at least `minSize` wide (the integrator uses 1.5 list radii), at most
// kMaxTiles of them. On a bounded axis the domain [lo, hi) is split into floor((hi - lo) /
// minSize) tiles (at least 1) and particles beyond it belong to the edge tiles; on a periodic
// axis the period is.
struct TileGrid {
  static constexpr std::uint32_t kMaxTiles = 1u << 16;
  float origin[4];   // xyz m; w: the largest half-sum of the two largest reaches the tiles allow (m)
  float invSize[4];  // xyz 1/m; w: the skin squared (m^2), for reference
  std::uint32_t count[4];  // xyz tiles per axis; w: bit a set when axis a is periodic
  // origin and counts from the domain; w of origin from the support 2h and the skin
  static TileGrid covering(glm::vec3 lo, glm::vec3 hi, std::uint32_t periodicAxes, float minSize, float support,
                           float skin);
  std::uint32_t tiles() const { return count[0] * count[1] * count[2]; }
  // A position's tile per axis, with the shader's float operations (hemo_tile_cell).
  glm::uvec3 cellOf(glm::vec3 x) const;
  std::uint32_t indexOf(glm::uvec3 c) const { return c.x + count[0] * (c.y + count[1] * c.z); }
};
static_assert(sizeof(TileGrid) == 48);

struct SphStatus {
  std::uint32_t firstBadStep = 0xffffffffu;  // none
  std::uint32_t nonFinite = 0;
  std::uint32_t neighbourOverflow = 0;
  std::uint32_t maxNeighbours = 0;
  std::uint32_t badInputId = 0xffffffffu;  // lowest id already non-finite entering a force pass
  std::uint32_t badForceId = 0xffffffffu;  // lowest id whose forces turned non-finite
  std::uint32_t openShortfall = 0;         // open inlet: images that found no free slot
};

// What DFSPH's solves did since the last reset (sph/dfsph_reduce.comp's stats).
struct PressureSolveStats {
  std::uint32_t lastIterations = 0;  // corrections of the last step's solve
  float lastError = 0.0f;            // its final mean error / rho0 (compression; divergence: d dt / rho0)
  std::uint32_t capHits = 0;         // solves that stopped at the cap above the tolerance
  std::uint32_t solves = 0;
  std::uint32_t totalIterations = 0;
  std::uint32_t maxIterations = 0;   // most corrections of one solve
  float worstError = 0.0f;           // the largest final mean compression of a solve
  double meanIterations() const { return solves > 0 ? double(totalIterations) / solves : 0.0; }
};

struct SphClock {
  double time = 0.0;  // s
  float lastDt = 0.0f;
  std::uint32_t steps = 0;
};

class SphSolver {
 public:
  // `domain` is the region the grid covers (cells of the list radius); particles outside it
  // still interact correctly but are counted as outside. On the settings' periodic axes the
  // domain [min, max) is one period: particles leaving it re-enter on the other side.
  SphSolver(gpu::Context& context, ParticleStore& particles, glm::vec3 domainMin, glm::vec3 domainMax,
            const SphSettings& settings, std::uint32_t maxStepsPerBatch = 256);

  // Records one whole step. `step` is the global step index, `logIndex` its slot in the step
  // log of the current batch (< maxStepsPerBatch). Steps after the clock reaches `endTime` (s)
  // change nothing.
  void recordStep(gpu::CommandRecorder& rec, std::uint32_t step, std::uint32_t logIndex, float endTime = 3.0e38f,
                  gpu::TimestampQueries* timestamps = nullptr);
  // Stages on their own, for tests. recordNeighbours always rebuilds (grid and list); the
  // others use the current list.
  void recordNeighbours(gpu::CommandRecorder& rec, gpu::TimestampQueries* timestamps = nullptr);
  // The same with the grid sorting only the slots [0, sorted) (NeighbourGrid::record).
  void recordNeighbours(gpu::CommandRecorder& rec, std::uint32_t sorted, gpu::TimestampQueries* timestamps = nullptr);
  // Density and pressure of fluid particles, then of boundary particles.
  void recordDensity(gpu::CommandRecorder& rec, gpu::TimestampQueries* timestamps = nullptr);
  void recordForces(gpu::CommandRecorder& rec);  // with the SPS stress pass first when enabled
  void recordIntegrate(gpu::CommandRecorder& rec, std::uint32_t step, std::uint32_t logIndex, float endTime = 3.0e38f);
  // DFSPH (PressureSolver::Dfsph only; the density passes run its divergence solve): after the
  // force pass, the solve that adds the pressure
  // acceleration for the step the integrator will take (interface/sph.h, "The pressure
  // solver"): the first prediction, then the cap's worth of gated (correction, prediction)
  // pairs, each followed by the reduction that decides on the next; with a wall, its share of
  // the solve's pressure (MassSpring::recordPressureReaction). `endTime` as the integrator's.
  void recordPressureSolve(gpu::CommandRecorder& rec, float endTime = 3.0e38f,
                           gpu::TimestampQueries* timestamps = nullptr);
  bool solvesPressure() const { return settings_.pressureSolver == PressureSolver::Dfsph; }
  // (a readback; zeros under WCSPH): the density solve's, or the divergence solve's
  PressureSolveStats readPressureSolveStats(bool divergence = false) const;
  // The gated (correction, prediction) regions recorded per solve, 1 to the cap (default: the
  // cap, settings().solverMaxIterations). Below the cap, a solve still open after the last
  // recorded region leaves the step unfinished and marks it (readSolveDepth().deeper): the
  // caller must then run the batch again from its start with more recorded
  // (Simulation::run does, from a copy of the state). Takes effect in the next recordStep.
  void setRecordedIterations(std::uint32_t regions);
  std::uint32_t recordedIterations() const { return recordedIterations_; }
  // Zeroes the depth words (a transfer command), before a batch.
  void recordSolveDepthReset(gpu::CommandRecorder& rec);
  struct SolveDepth {
    std::uint32_t maxIterations = 0;  // most corrections of one solve since the reset
    std::uint32_t deeper = 0;         // solves left open after the last recorded region
  };
  SolveDepth readSolveDepth() const;  // (a readback)
  // vec4 per slot: k_i = kappa_i / rho_i of the last prediction (m^5 kg^-1 s^-2), the pressure
  // of the step's impulses (Pa; state().y holds it plus the background pressure), the
  // divergence solve's sum of k_i, 0.
  const gpu::Buffer& solveStiffness() const { return kappa_; }
  // Between list builds the force evaluations update only the boundary and wall particles
  // with fluid in their list; the others keep the state the last build gave them. This sets
  // those to the last force evaluation's time (its background pressure), for output. It
  // changes nothing any later step reads. Records nothing before the first density pass.
  void recordBoundaryRest(gpu::CommandRecorder& rec);

  // Makes the wall particles of `network` (kind HEMO_KIND_WALL) move as mass points of its
  // springs: every force evaluation then runs the wall stages after the fluid's forces.
  // Set-up only, before the first step.
  void attachWall(const SpringNetwork& network);
  const MassSpring* wall() const { return wall_.get(); }
  MassSpring* wall() { return wall_.get(); }
  // Tools that press on the fluid and the wall (hemo/sim/tools.hpp): every force evaluation
  // then runs their contact pass after the wall's, and every step logs their force and pose
  // at its index in the batch (ToolContact::readLog). Set-up only, after attachWall (the
  // tools push the wall's free points) and before the first step; throws
  // std::invalid_argument for bad tools.
  void attachTools(const std::vector<ToolSpec>& tools);
  const ToolContact* tools() const { return tools_.get(); }
  ToolContact* tools() { return tools_.get(); }
  // The open ends' refill of the inlet buffer (hemo/sim/inflow.hpp, sph/open_spawn.comp), on
  // its own, for tests (recordStep records it inside the rebuild gate, before the grid).
  void recordOpenRefill(gpu::CommandRecorder& rec);
  bool openEnds() const { return openOn_; }
  // Open ends: the crossing counters (HEMO_OPEN_COUNTER_* of interface/sph.h), a readback.
  // in, inBack, parkedStart: the inlet's crossings into the lumen and back, and its parked;
  // out, outBack, parkedEnd: the outlets' together, out of the lumen and back in, and parked;
  // spawned: every end's images.
  struct OpenCounts {
    std::uint32_t in = 0, inBack = 0, out = 0, outBack = 0, parkedEnd = 0, parkedStart = 0, spawned = 0;
    std::uint32_t parkedOutside = 0;  // left the domain across the axis (through a tear)
    // Per end (the inlet, then the outlets): left its buffer into the lumen, came into it from
    // the lumen, parked past its end, spawned into its buffer.
    struct End {
      std::uint32_t leave = 0, enter = 0, parked = 0, spawned = 0;
    };
    std::vector<End> ends;
  };
  OpenCounts readOpenCounts() const;
  const gpu::Buffer& pending() const { return pending_; }
  gpu::Buffer& pending() { return pending_; }  // (for tests)
  gpu::Buffer& openCounters() { return openCounters_; }  // HEMO_OPEN_COUNTER_* (for tests)
  gpu::Buffer& openProfile() { return openProfile_; }    // the ends' speeds and pressures (for tests)
  // Open ends with an escape distance (OpenEnds::parkBeyond): the mask of their escape grid,
  // a bit per cell (scene::escapeMask). Set-up only (an upload); throws std::invalid_argument
  // when its size is not the grid's.
  void setEscapeMask(const std::vector<std::uint32_t>& words);
  // Drives the fluid in a vessel's inflow zone (hemo/sim/inflow.hpp). Set-up only (an upload);
  // throws std::invalid_argument for a bad inflow. Without it no particle is driven.
  void setInflow(const Inflow& inflow);
  // The background (lumen) pressure p_bg (Pa) from the next step on: an upload, between
  // batches. A ramp still rising goes on towards the new value. Throws std::invalid_argument
  // if it is not finite.
  void setBackgroundPressure(float pascals);

  // Resets clock, status and counters (set-up; records transfer commands).
  void recordReset(gpu::CommandRecorder& rec);
  // Makes the next recorded step rebuild the grid and the neighbour list whatever the
  // particles' reach (as the first step after a reset does): for profiling the rebuild.
  void recordRebuildRequest(gpu::CommandRecorder& rec);

  const SphSettings& settings() const { return settings_; }
  const SphParams& params() const { return params_; }
  const NeighbourGrid& grid() const { return grid_; }
  NeighbourGrid& grid() { return grid_; }
  const gpu::Buffer& state() const { return state_; }     // vec4 (rho, p, d rho/dt with continuity density and RK2, else 0, 0) per slot
  const gpu::Buffer& accel() const { return accel_; }     // vec4 (a, 0) per slot
  // Non-Newtonian blood: each fluid slot's viscosity at the last force evaluation, a float
  // (Pa s, over SphSettings::viscousLatticeFactor; interface/sph.h, "Viscosity").
  const gpu::Buffer& viscosities() const { return viscosity_; }
  const gpu::Buffer& dtLimits() const { return dtLimit_; }
  // vec2 (min, max) of those limits at the last force evaluation (the wall stage's included),
  // reduced on the GPU for the integrator's dt (common/dt_fold.glsl).
  const gpu::Buffer& stepLimits() const { return dtResult_; }
  const gpu::Buffer& neighbourCounts() const { return ncount_; }
  // The neighbour list of the slots [0, listPageSlots()), the first page (all of it when the
  // list is one page).
  const gpu::Buffer& neighbourList() const { return nlist_.front(); }
  // The list and the interacting pairs in pages of listPageSlots() slots (a power of two), each
  // its own buffer, when one buffer for all slots would pass a binding limit of the device
  // (maxStorageBufferRange, maxTexelBufferElements, the largest allocation): the passes that
  // walk them run once per page (interface/sph.h, "pages").
  // Whether the passes walk the grid's cells instead of a list (NeighbourSearch; the list's
  // buffers are then placeholders, one page).
  bool walksCells() const { return cellWalk_; }
  std::uint32_t listPages() const { return static_cast<std::uint32_t>(nlist_.size()); }
  std::uint32_t listPageSlots() const { return pageSlots_; }
  const gpu::Buffer& neighbourListPage(std::uint32_t page) const { return nlist_.at(page); }
  const gpu::Buffer& interactingPairsPage(std::uint32_t page) const { return pairList_.at(page); }
  // A neighbour-list entry is a slot, with kListBoundaryBit set for a boundary or wall
  // neighbour (interface/sph.h); the interacting-pair list holds plain slots, the fluid pairs
  // from entry 0 up and the boundary pairs from entry capacity - 1 down, and its count packs
  // fluid | boundary << 16.
  static constexpr std::uint32_t kListBoundaryBit = 0x80000000u;
  // List entries the pair passes read per texel: 4 with the contiguous layout and a capacity
  // that is a multiple of 4, else 1 (common/sph_params.glsl, hemo_list_texel).
  std::uint32_t listReadWidth() const { return listWidth_; }
  // A pair pass's specialization constants: its own (1, 2, ...), then the periodic axes at
  // HEMO_SPEC_PERIODIC_AXES (interface/sph.h); the wall's reaction pass uses it too.
  std::vector<std::uint32_t> pairSpecialization(std::vector<std::uint32_t> constants) const;
  // A fluid particle's list entries within interaction range at the last density pass, in
  // list order and layout (interface/sph.h, HEMO_DENSITY_BINDING_PAIR_LIST), and their number.
  const gpu::Buffer& interactingPairCounts() const { return pairCount_; }
  const gpu::Buffer& interactingPairs() const { return pairList_.front(); }
  // Clusters (interface/sph.h, "Clusters"): whether the fluid passes walk them (they do while
  // the slots are in grid order), whether the boundary particles' slots are in clusters too
  // (then numbered after the fluid's, without per-particle lists), the entries per cluster,
  // and the lists as the last build left them: a count per cluster (front | back << 16: the
  // back holds the boundary entries within the repulsion's reach, interface/sph.h) and
  // clusterCapacity() entries per cluster; and the fluid clusters' walk order (a uint per
  // cluster, sph/cluster_order.comp).
  bool usesClusters() const { return clusterPath(); }
  bool usesBoundaryClusters() const { return boundaryClusterPath(); }
  std::uint32_t clusterCapacity() const { return clusterCapacity_; }
  // The boundary pass's active list's indirect arguments: uvec4 (groups x, y, z, entries).
  const gpu::Buffer& boundaryActiveArgs() const { return activeArgs_; }
  const gpu::Buffer& clusterCounts() const { return ccount_; }
  const gpu::Buffer& clusterLists() const { return clist_; }
  const gpu::Buffer& clusterOrder() const { return corder_; }
  // The boundary clusters' active list (uint per cluster, numbered from the first boundary
  // cluster): as the sorting mode appended it, and in the walk order the evaluations take;
  // its length is the w of the indirect arguments (uvec4).
  const gpu::Buffer& activeAppended() const { return activeAppended_; }
  const gpu::Buffer& activeList() const { return activeSlots_; }
  const gpu::Buffer& activeArgs() const { return activeArgs_; }
  const gpu::Buffer& stepLog() const { return log_; }     // vec2 (t, dt) per batch step
  // The last step's rebuild test: vec4 (min, max of the x displacements since the list
  // build, the half-sum of the two largest reaches, the middle of the range a step before), m
  // (sph/integrate.comp).
  const gpu::Buffer& rebuildCheck() const { return checkResult_; }
  // The tile test of the last symplectic step (interface/sph.h, "the tile test"): its grid,
  // and a float, the largest separation of neighbouring tiles' displacement boxes (m; +inf
  // when that step did not collect the boxes; RK2 steps do not run the test).
  const TileGrid& tileGrid() const { return tileSpec_; }
  const gpu::Buffer& tileCheck() const { return tileResult_; }
  const gpu::Buffer& paramsBuffer() const { return paramsBuffer_; }
  // The clock's two records and which one holds the current time (after the recorded steps).
  const gpu::Buffer& clockBuffer() const { return clock_; }
  std::uint32_t clockParity() const { return clockParity_; }
  // Half the list's skin, m: recordStep rebuilds the list once the two largest reaches (the
  // distances particles moved since the build, relative to the drift of the middle) sum to
  // more than twice this, unless (symplectic Euler) the tile test shows the list still holds.
  float rebuildThreshold() const;

  SphStatus readStatus() const;
  SphClock readClock() const;
  // The same from copies of the status words (HEMO_STATUS_COUNT uint) and of the clock's two
  // records (32 bytes), as a batch's report holds them (Simulation).
  const gpu::Buffer& statusBuffer() const { return status_; }
  static SphStatus statusFrom(const std::uint32_t* words);
  SphClock clockFrom(const void* records) const { return clockFrom(records, clockParity_); }
  // The clock's current record alternates each step: `parity` is clockParity() as it was
  // after recording the steps the copy followed (a pipelined run has recorded more since).
  static SphClock clockFrom(const void* records, std::uint32_t parity);

  // Checkpoints (hemo/io/checkpoint.hpp): every buffer of the solver, its grid, its rebuild
  // gate and its wall, in a fixed order (those of a path the scene does not take are
  // placeholders, listed as well); and the host's recording state (which clock record is
  // current, what the last build left in order, whether the gate must be armed, ...), which
  // restoreHostState takes back. Between batches only.
  void checkpointBuffers(std::vector<gpu::Buffer*>& out);
  std::vector<std::uint32_t> hostState() const;
  // Throws std::invalid_argument for a state of another length.
  void restoreHostState(const std::vector<std::uint32_t>& state);
  // Neighbour-list rebuilds since the last reset (a readback).
  std::uint32_t readRebuilds() const;

 private:
  gpu::Context* context_;
  ParticleStore* particles_;
  SphSettings settings_;
  SphParams params_;
  std::uint32_t maxStepsPerBatch_;
  std::uint32_t clockParity_ = 0;  // which clock record holds the current time
  // The integrator over the first `moving` slots (the rest must be rigid boundary particles).
  void recordIntegrateMode(gpu::CommandRecorder& rec, std::uint32_t step, std::uint32_t logIndex, float endTime,
                           std::uint32_t mode, std::uint32_t moving, gpu::TimestampQueries* timestamps = nullptr);
  bool inGridOrder() const;  // the slots are sorted since the last upload (fluid first)
  // The boundary-pressure pass in a range mode (HEMO_BPRESSURE_SORT or _REST) over the
  // non-fluid slots.
  void recordBoundaryRange(gpu::CommandRecorder& rec, std::uint32_t mode, std::uint32_t clockIn);
  std::uint32_t movingSlots() const;
  // The density pass over the first `fluidSlots` slots (boundary pressure over the active
  // list), and the force passes likewise (the wall stage from nonFluidStart()).
  void recordDensityOver(gpu::CommandRecorder& rec, std::uint32_t fluidSlots,
                         gpu::TimestampQueries* timestamps = nullptr);
  std::uint32_t nonFluidStart() const;  // the first slot that may hold a non-fluid particle
  void recordForcesOver(gpu::CommandRecorder& rec, std::uint32_t fluidSlots,
                        gpu::TimestampQueries* timestamps = nullptr);
  NeighbourGrid grid_;
  std::unique_ptr<ToolContact> tools_;
  std::uint32_t toolLogIndex_ = 0;  // the step's index in the batch, for the tools' log
  gpu::Buffer toolPlaceholder_;     // bound to the time-step reduction's tool slots without tools
  void makeDtReduceSet();
  gpu::Buffer paramsBuffer_;
  std::uint32_t listWidth_ = 1;  // list entries per texel read (1 or 4)
  bool cellWalk_ = false;        // NeighbourSearch::Cells in effect (walksCells())
  std::uint32_t periodicAxes_ = 0;  // bit a: axis a is periodic (HEMO_SPEC_PERIODIC_AXES)
  gpu::Buffer state_, accel_, dtLimit_, ncount_, pairCount_, viscousVel_;
  // The lists' pages (listPages()) of pageSlots_ slots each.
  std::vector<gpu::Buffer> nlist_, pairList_;
  std::uint32_t pageSlots_ = 0;
  // Records fn(page, first, end) for each page that holds some of the slots [begin, end), with
  // a barrier between them: a page's dispatch writes records of buffers (state, partials) that
  // the others bind whole, and the layer's synchronization validation cannot tell the records
  // apart. (Pages exist only in scenes of millions of particles, where a barrier costs little.)
  template <class Fn>
  void forEachPage(gpu::CommandRecorder& rec, std::uint32_t begin, std::uint32_t end, Fn fn) const {
    bool first = true;
    forEachListPage(pageSlots_, listPages(), begin, end, [&](std::uint32_t p, std::uint32_t lo, std::uint32_t hi) {
      if (!first) rec.computeToCompute();
      first = false;
      fn(p, lo, hi);
    });
  }
  // Clusters (interface/sph.h): their lists' capacity, counts and entries.
  std::uint32_t clusterCapacity_ = 0;
  gpu::Buffer ccount_, clist_, corder_;
  const gpu::ComputePipeline* buildClusters_ = nullptr;
  const gpu::ComputePipeline* clusterOrder_ = nullptr;
  const gpu::ComputePipeline* densityClusters_ = nullptr;
  const gpu::ComputePipeline* forcesClusters_ = nullptr;
  const gpu::ComputePipeline* boundaryClusters_ = nullptr;
  gpu::DescriptorSet buildClustersSet_, clusterOrderSet_, densityClustersSet_, forcesClustersSet_, boundaryClustersSet_;
  gpu::DescriptorSet boundaryOrderSet_, boundaryClustersSortSet_;
  bool clusters_ = false;  // the layout asks for clusters (they run while clusterPath())
  // The fluid passes walk the clusters' lists in this step: the layout asks for them and the
  // slots are in grid order (the fluid's first).
  bool clusterPath() const;
  std::uint32_t clusterCount() const;  // clusters of the fluid's slots (the last may hold fewer)
  // The boundary slots are in clusters too (numbered from clusterCount() on): on the cluster
  // path in a scene without wall particles.
  bool boundaryClusterPath() const;
  std::uint32_t boundaryClusterCount() const;  // clusters of the slots past the fluid's
  gpu::Buffer pairPosition_;  // (x, V p) per particle: what the force pass gathers with viscousVel_ (interface/sph.h)
  // The boundary and wall slots with fluid in their list, and the indirect arguments of the
  // boundary-pressure pass over them (interface/sph.h, HEMO_BPRESSURE_SORT); with boundary
  // clusters, the active clusters as appended, before sph/cluster_order.comp sorts them into
  // activeSlots_.
  gpu::Buffer activeSlots_, activeArgs_, activeAppended_;
  gpu::Buffer integrateArgs_;  // the integrator's two variants' indirect arguments
  std::uint32_t boundaryClockIn_ = ~0u;  // the clock record of the last boundary-pressure pass (~0: none since the reset)
  gpu::Buffer clock_, status_, log_;
  gpu::Buffer inflow_;  // InflowParams
  gpu::Buffer savedPos_, savedVel_, stepDt_;  // RK2: state at the start of the step, its dt
  gpu::Buffer tauA_, tauB_;  // SPS stress per density (16 bytes each when SPS is off)
  gpu::Buffer viscosity_;    // non-Newtonian blood: mu per fluid slot (4 bytes for Newtonian blood)
  // The time step's reduction: partials of the force pass and the wall stage (vec2 per SIMD
  // group; common/dt_fold.glsl), how many each wrote, and the result (min, max) that
  // sph/dt_reduce.comp reduces them to.
  gpu::Buffer dtPartials_, dtCounts_, dtResult_;
  // The rebuild test: the integrator's partials (one per SIMD group) and their count, and the
  // result sph/rebuild_decide.comp reduces them to (min d.x, max d.x, half-sum of the two
  // largest reaches, middle of the range a step before).
  gpu::Buffer checkPartials_, checkCount_, checkResult_;
  // The tile test: its grid (uniform), boxes (HEMO_TILE_WORDS per tile), result, occupied
  // tiles; the pass that marks the tiles of rigid boundary particles, the decision pass
  // (sph/rebuild_decide.comp, with and without the tile test), and the upload the marks are of.
  TileGrid tileSpec_;
  gpu::Buffer tileGrid_, tileBoxes_, tileResult_, tileOccupied_;
  const gpu::ComputePipeline* tileStatic_;
  const gpu::ComputePipeline* rebuildDecide_[2];  // without, with the tile test
  gpu::DescriptorSet tileStaticSet_, rebuildDecideSet_;
  std::uint64_t tileUpload_ = ~std::uint64_t(0);
  std::unique_ptr<MassSpring> wall_;
  gpu::DispatchGate rebuildGate_;
  // DFSPH (a texel's worth each under WCSPH): kappa_i / rho_i per slot, the prediction's
  // partials (uint per workgroup), the stats (HEMO_DFSPH_STAT_*), the gate of the iterations.
  gpu::Buffer kappa_, solvePartials_, solveStats_;
  gpu::DispatchGate pressureGate_;
  // HEMO_DFSPH_DEPTH_* (not part of the state: what the batch asked of the recording)
  gpu::Buffer solveDepth_;
  std::uint32_t recordedIterations_ = 0;
  const gpu::ComputePipeline* dfsphPredict_ = nullptr;
  const gpu::ComputePipeline* dfsphCorrect_ = nullptr;
  const gpu::ComputePipeline* dfsphReduce_ = nullptr;
  gpu::DescriptorSet dfsphPredictSet_, dfsphCorrectSet_, dfsphReduceSet_;
  // mode: HEMO_DFSPH_MODE_DENSITY or _DIVERGENCE (interface/sph.h)
  void recordPressureSolveOver(gpu::CommandRecorder& rec, std::uint32_t fluidSlots, float endTime,
                               gpu::TimestampQueries* timestamps, std::uint32_t mode);
  const gpu::ComputePipeline* buildList_;
  const gpu::ComputePipeline* density_;
  const gpu::ComputePipeline* boundaryPressure_;
  const gpu::ComputePipeline* spsStress_;
  const gpu::ComputePipeline* forces_;
  const gpu::ComputePipeline* dtReduce_;
  gpu::DescriptorSet dtReduceSet_;
  // by stage (HEMO_INTEGRATE_*; index 3: symplectic Euler collecting the tile boxes), without
  // and with the inflow zone's code (made on the first setInflow: scenes without one never
  // compile it)
  const gpu::ComputePipeline* integrate_[3][4] = {};
  std::uint32_t continuity_ = 0;  // the integrator's constant 1
  bool inflowOn_ = false;        // setInflow has given a zone: the integrator with its code
  bool openOn_ = false;          // ... with open ends (the integrator's constant 3 = 2, the refill)
  std::uint32_t openEnds_ = 0;   // ... how many (the inlet and the outlets)
  // inflow: 0 none, 1 the zone, 2 the zone with open ends (the integrator's constant 3)
  const gpu::ComputePipeline& integratePipeline(std::uint32_t mode, std::uint32_t inflow, bool collect = false);
  std::uint32_t inflowVariant() const { return openOn_ ? 2u : inflowOn_ ? 1u : 0u; }
  // Open ends (hemo/sim/inflow.hpp): the crossing counters (HEMO_OPEN_COUNTER_*) and the
  // crossers' flags (uint per slot), bound to the integrator in every scene (4 bytes per slot);
  // the refill's scan of the flags, the crossers by rank, its scan and pass (made by setInflow).
  gpu::Buffer openCounters_, pending_, spawnScan_, crossers_;
  // Open ends: the integrator's sums of the axial speeds by bin (and the pressure) next to each plane and the
  // profiles sph/open_profile.comp makes of them (common/inflow.glsl, HEMO_OPEN_BINS).
  gpu::Buffer openSums_, openProfile_;
  gpu::Buffer escapeMask_;  // open ends' escape mask (EscapeGrid; a word without open ends)
  const gpu::ComputePipeline* openProfilePass_ = nullptr;
  gpu::DescriptorSet openProfileSet_;
  std::unique_ptr<gpu::PrefixScan> spawnScanner_;
  const gpu::ComputePipeline* spawn_ = nullptr;
  gpu::DescriptorSet spawnSet_;
  // The symplectic-Euler integrator's two variants run by indirect arguments (integrateArgs_)
  // that the rebuild decision writes for the next step (sph/rebuild_decide.comp): valid once a
  // decision has been recorded for these workgroups since the host last reset the test.
  bool integrateArgsValid_ = false;
  gpu::Groups integrateArgsGroups_;
  gpu::DescriptorSet integrateSet_;
  // one per page of the list
  std::vector<gpu::DescriptorSet> buildListSets_, densitySets_, spsSets_, boundarySets_, forcesSets_;
  // The gate must be armed by its own pass before the next step (after a reset or a rebuild
  // request); otherwise the last step's rebuild check has armed it.
  bool armPending_ = true;
  std::uint64_t sortedUpload_ = ~std::uint64_t(0);  // the store upload a rebuild has sorted
  // staticSlots: the slots past n hold rigid boundary particles, which count as displacement 0.
};

}  // namespace hemo::sim
