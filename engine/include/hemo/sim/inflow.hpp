#pragma once
// Driven inflow of a periodic vessel. A slab of the lumen at the start of the tube (the
// inflow zone, x in [zoneStart, zoneEnd)) moves at a prescribed axial velocity: every fluid
// particle that starts a step inside it within the tube's radius gets
//   v_x = u(t) f(r),  f = 2 (1 - r^2 / R^2) (parabolic) or 1 (plug),
// while across the section it moves under the SPH forces as anywhere (so particles that enter
// the zone too close can part; a fully kinematic zone froze them together). u(t) is the mean
// speed over the cross-section: u(t) = U w(t) ramp(t), U the mean speed,
// w a periodic waveform (samples over one period, linearly interpolated; 1 when constant),
// ramp(t) = min(t / ramp, 1). Fluid that leaves the far end of the tube comes back through the
// periodic seam into the zone: the outflow is recycled to the inlet and the particle budget
// never changes. The zone acts as a pump: it sets the flow rate whatever the pressure, and
// keeps pushing blood through a rupture. Evaluated on the GPU in sph/integrate.comp.
//
// A pump does not add blood, and a closed loop of weakly compressible fluid loses its
// pressure as the wall stretches (p falls by about 7 B dV/V) and as blood leaves through a
// rupture. With holdPressure the zone is also the supply that keeps the lumen at its pressure:
// every step each zone particle away from the wall (r < R - dp) moves its mass a tenth of the
// way towards the one that brings its summed density to the rest density rho0 (pressure p_bg,
// the lumen pressure), m <- m (1 + (rho0 / rho - 1) / 10), kept between the initial mass m0 and
// maxMassRatio m0 (two-sided, so the scatter of single densities does not ratchet the mass
// up; sph/integrate.comp says why a tenth and why not at the wall). Under DFSPH the fraction is
// a tenth per acoustic step C_a h / c0 (at most a half), the same rate per second as under
// WCSPH with its longer steps. The flow carries the mass
// downstream; particles that took it up
// stand for proportionally more volume (their spacing grows as (m / m0)^(1/3) at rest
// density), and the cap bounds how long a bleed can be fed.
//
// Open ends (Inflow::open): the vessel is not periodic. Each end (the inlet, and one or more
// outlets: a branching vessel has several) has its own frame: the centre of the vessel's end, the axis into the lumen, the lumen's radius
// there. The slab of the lumen a buffer length in from the end is the end's buffer; past it
// lies the lumen. The inlet buffer moves at the inflow's profile and speed (the velocity
// inlet), a single outlet's buffer at the same flow rate (a flow-controlled outlet) or, as a
// pressure end (below), holds a pressure (several outlets are pressure ends: a flow split
// would need its ratios). Fluid past any end, or out of the domain through a tear,
// is parked (HEMO_KIND_PARKED of interface/sph.h: a free fluid slot far outside the domain,
// which no pass sees), and every particle that leaves a buffer into the lumen gets its image a
// buffer length back along the end's axis, at the buffer's far end, in a parked slot
// (sph/open_spawn.comp), so each buffer always holds the same particles, as if it were fed
// through a periodic seam (an outlet's only when the flow reverses). The refill runs on the
// GPU at the start of every step that rebuilds the neighbour list; a crosser still owed its
// image forces a rebuild once it is `pendingMargin` into the lumen, so the gap at the buffer's
// far end never reaches within the support of the buffer particles the lumen sees. The
// crossings of both planes are counted (integers), so the lumen's mass balance is known
// exactly. An end acts only within `reach` of its axis, and from `reach` behind its end to its
// plane (the end's region): there it drives and parks fluid, and counts its crossings; the
// rest of the domain, other branches of a curved vessel included, it leaves alone.
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <cstddef>

#include <cstdint>
#include <optional>
#include <vector>

namespace hemo::sim {

// One open end's frame (see above). Along the axis from the origin, s < 0 is past the end
// (parked), [0, length) the buffer, length and on the lumen.
struct OpenEnd {
  glm::vec3 origin{0.0f};         // m, the centre of the vessel's end
  glm::vec3 axis{1.0f, 0.0f, 0.0f};  // unit, into the lumen
  float radius = 0.0f;            // m, the lumen's radius at the end
  float length = 0.0f;            // m, the buffer's along the axis
  float reach = 0.0f;             // m, of the end's region from the axis (the lumen and its wall)
  // A pressure end (OpenEnds): its buffer holds this pressure over the background pressure
  // (Pa; the inlet's rises over the inflow's ramp and follows its waveform).
  bool pressure = false;
  float pressurePa = 0.0f;
  // A crosser's image lies at its position less this (a buffer length along the axis, in
  // single precision as the GPU takes it).
  glm::vec3 shift() const { return axis * length; }
  // (s, r^2): the distance along the axis from the origin and the squared distance from the
  // axis, in double precision.
  glm::dvec2 local(glm::dvec3 p) const;
  // Whether p lies in the buffer, s in [0, length) within reach.
  bool inBuffer(glm::dvec3 p) const;
};

// Where blood outside the vessel is parked before it leaves the domain (OpenEnds::parkBeyond):
// the domain in cubic cells of `cell` m from `origin`, cell k = x + nx (y + ny z); bit k of the
// mask (word k / 32) is set where all of the cell lies farther than parkBeyond outside the
// vessel's wall (scene::escapeMask builds it from the vessel's geometry).
struct EscapeGrid {
  glm::vec3 origin{0.0f};
  float cell = 0.0f;  // m (0: no grid)
  glm::uvec3 dims{0u};
  std::size_t words() const { return (std::size_t(dims.x) * dims.y * dims.z + 31) / 32; }
  // Cells of two spacings over the domain [lo, hi].
  static EscapeGrid over(glm::vec3 lo, glm::vec3 hi, float spacing);
  glm::vec3 centre(std::size_t k) const;
};

struct OpenEnds {
  static constexpr std::uint32_t kMaxEnds = 8;  // the inlet and up to 7 outlets
  OpenEnd inlet;
  std::vector<OpenEnd> outlets;
  std::size_t endCount() const { return 1 + outlets.size(); }
  // End k: the inlet (0), then the outlets.
  const OpenEnd& end(std::size_t k) const { return k == 0 ? inlet : outlets.at(k - 1); }
  // Blood farther than this outside the vessel's wall is parked (and counted as escaped), so a
  // bleed frees its slots for the buffers without waiting for the blood to leave the domain
  // (m; 0: only blood that leaves the domain). The mask of the grid's cells where that holds.
  float parkBeyond = 0.0f;
  EscapeGrid escape;
  float pendingMargin = 0.0f; // m (see above)
  glm::vec3 parking{0.0f};    // m, where parked slots lie (outside the domain, beyond every support)
  glm::vec3 boxMin{-3.0e38f}, boxMax{3.0e38f};  // m, the domain: fluid beyond is parked
  // Pressure ends (OpenEnd::pressure): a buffer that holds its pressure instead of the Tait
  // law's, and moves at the lumen's axial velocity next to its plane, radius by radius (a zero
  // gradient along the axis), from a slab of `slab` m (Tafuni et al. 2018 prescribe the
  // pressure and extrapolate the velocity likewise). Without: the inlet moves at the inflow's
  // profile, and so does a single outlet (a flow-controlled outlet). A pressure inlet needs
  // pressure outlets, and so do several outlets.
  float slab = 0.0f;            // m
  // Each pressure end's buffer also moves faster by the pressure the lumen next to its plane
  // has in excess of the outlet's (the inlet: lacks of the inlet's) times this, 1 / (rho0 c0)
  // (m/s per Pa): the outgoing characteristic of the acoustic waves (u + p / (rho c) carried
  // out), which sets a lumen at rest between buffers at rest in motion and lets the pressure
  // waves leave instead of reflecting.
  float characteristic = 0.0f;
};

struct Inflow {
  enum class Profile { Parabolic, Plug };
  Profile profile = Profile::Parabolic;
  // The periodic vessel's zone (open ends: each end's frame, OpenEnds, and the inlet's here
  // only where its axis is x)
  float zoneStart = 0.0f;  // m along x
  float zoneEnd = 0.0f;    // m
  float centreY = 0.0f;    // m, the tube's axis
  float centreZ = 0.0f;    // m
  float radius = 0.0f;     // m, the lumen's radius (particles farther out are not driven)
  float meanSpeed = 0.0f;  // U (m/s), mean over the cross-section (may be negative: flow along -x)
  float period = 0.0f;     // s, of the waveform (0: constant)
  std::vector<float> waveform;  // w at t = k period / n, k = 0..n-1 (empty: constant)
  float ramp = 0.0f;       // s: u rises linearly from 0 over this time (0: at once)
  bool holdPressure = false;   // the zone supplies mass to hold the lumen at rho0 (see above)
  float maxMassRatio = 4.0f;   // cap of a particle's mass / the initial mass
  std::optional<OpenEnds> open;  // open ends (see above); none: a periodic vessel

  static constexpr std::uint32_t kMaxSamples = 64;

  // Mean speed u(t) (m/s) and the axial velocity at distance r from the axis, in double
  // precision: the CPU reference of the GPU evaluation.
  double meanSpeedAt(double t) const;
  double axialVelocity(double t, double r) const;
  // Throws std::invalid_argument naming the problem.
  void validate() const;
};

// Mirror of the GLSL InflowParams block (compute_shaders/common/inflow.glsl), std430.
struct InflowParams {
  float zoneStart, zoneEnd, centreY, centreZ;
  float radius, meanSpeed, period, ramp;
  std::uint32_t profile, samples, enabled, holdPressure;
  float restDensity, maxMass, baseMass, reserved;
  float waveform[Inflow::kMaxSamples];
  struct End {
    float origin[4];  // xyz m; w: the buffer's length (m)
    float axis[4];    // xyz into the lumen; w: the lumen's radius (m)
    float shift[4];   // xyz: a crosser's image lies at its position less this (m); w: the reach (m)
    float drive[4];   // x: a flow outlet's speed over the inlet's, (R_inlet / R_outlet)^2;
                      // y: a pressure end's pressure (Pa over the background); z: 1 for a pressure end
  } ends[OpenEnds::kMaxEnds];  // the inlet's, the outlets'
  float parking[4];   // xyz m
  float pendingMargin;
  std::uint32_t open, endCount, reserved2;
  float slab[4];       // x: the pressure ends' slab (m); y: 1 / (rho0 c0)
  float boxMin[4];     // the domain (m; xyz)
  float boxMax[4];
  float escapeOrigin[4];         // EscapeGrid: xyz m; w: 1 / cell (1/m)
  std::uint32_t escapeDims[4];   // xyz cells; w: 1 where the mask parks blood
};
static_assert(sizeof(InflowParams) == 64 + 4 * Inflow::kMaxSamples + OpenEnds::kMaxEnds * 64 + 112);

// `restDensity` rho0 (kg/m^3) and `particleMass` m0 (kg) of the fluid.
InflowParams makeInflowParams(const Inflow& inflow, float restDensity, float particleMass);
InflowParams disabledInflowParams();

}  // namespace hemo::sim
