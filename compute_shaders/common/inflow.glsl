// One open end (hemo/sim/inflow.hpp, OpenEnd): along its axis from its origin, s < 0 is past
// the end, [0, length) its buffer, and the lumen beyond; it acts within `reach` of its axis.
struct HemoOpenEnd {
  vec4 origin;  // xyz: the centre of the vessel's end (m); w: the buffer's length (m)
  vec4 axis;    // xyz: unit, into the lumen; w: the lumen's radius there (m)
  vec4 shift;   // xyz: a crosser's image lies at its position less this (m); w: the reach (m)
  vec4 drive;   // x: a flow outlet's speed over the inlet's, (R_inlet / R_outlet)^2; y: a pressure
                // end's pressure over the background (Pa; the inlet's follows the inflow's
                // waveform and ramp, common/inflow_speed.glsl); z: 1 for a pressure end
};

// The driven inflow zone of a vessel (hemo/sim/inflow.hpp has the model), bound as a uniform
// buffer (std140; the C++ struct's float[64] is the vec4[16] here, sample k at
// waveform[k / 4][k % 4]).
struct InflowParams {
  float zoneStart;  // m along x
  float zoneEnd;
  float centreY;    // m, the tube's axis
  float centreZ;
  float radius;     // m
  float meanSpeed;  // U (m/s)
  float period;     // s (0: constant)
  float ramp;       // s
  uint profile;     // 0 parabolic, 1 plug
  uint samples;     // waveform samples over one period
  uint enabled;
  uint holdPressure;  // the zone supplies mass, relaxing towards m rho0 / rho within [baseMass, maxMass]
  float restDensity;  // rho0 (kg/m^3)
  float maxMass;      // kg, cap of a particle's mass
  float baseMass;     // kg, the initial particle mass (the floor)
  float reserved1;
  vec4 waveform[16];
  // Open ends (hemo/sim/inflow.hpp; open = 0: the periodic vessel above): each end's frame,
  // the inlet's then the outlets' (HemoOpenEnd; endCount of them).
  HemoOpenEnd ends[HEMO_OPEN_MAX_ENDS];
  vec4 parking;       // xyz: where parked slots lie (m)
  float pendingMargin; // m past an end's plane into the lumen at which a crosser still owed its image forces the refill (sph/integrate.comp)
  uint open;          // 1: open ends
  uint endCount;      // ends in use
  uint reserved2;
  // (pressure ends) x: the width of the lumen's slab next to each plane whose axial velocity
  // profile the buffer takes (m); y: 1 / (rho0 c0) (m/s per Pa)
  vec4 slab;
  vec4 boxMin;  // xyz: the domain (m); fluid beyond it is parked
  vec4 boxMax;
  // Blood far outside the vessel's wall is parked too (hemo/sim/inflow.hpp, EscapeGrid): the
  // mask's grid, xyz its origin (m), w 1 / its cell (1/m); its cells, and w = 1 where it is on.
  vec4 escapeOrigin;
  uvec4 escapeDims;
};

// Open end e's (s, r^2) at x: the distance along its axis from its origin, and the squared
// distance from its axis (a macro, as below).
#define hemo_open_local(block, e, x) hemo_open_local_of((x) - (block).ends[e].origin.xyz, (block).ends[e].axis.xyz)
vec2 hemo_open_local_of(vec3 d, vec3 axis) {
  const float s = dot(d, axis);
  const vec3 across = d - s * axis;
  return vec2(s, dot(across, across));
}

// The open ends' velocity profiles (pressure ends): HEMO_OPEN_BINS bins of equal area over the
// lumen's cross-section (bin = floor(bins r^2 / R^2)) per end, then one bin of pressure per
// plane (interface/sph.h, HEMO_OPEN_PRESSURE). The integrator sums each bin's axial velocities (pressures) of
// the lumen's particles in the slab next to the plane, in fixed point (HEMO_OPEN_SUM_WORDS
// words per bin: the low and high words of sum((v_x + offset) scale) and the count; integer
// sums, the same in any order); sph/open_profile.comp turns them into the mean speeds the next
// step's buffers move at, and the planes' pressures into the speed each buffer adds.
// (HEMO_OPEN_BINS and the fixed-point constants: interface/sph.h, shared with the host)
uint hemo_open_bin(float s2) {
  return min(uint(max(s2, 0.0) * float(HEMO_OPEN_BINS)), HEMO_OPEN_BINS - 1u);
}

// Sample k of the waveform of the block `block` (a macro: a function taking the struct by
// value copies all of it, waveform included, into per-invocation memory; the integrator's stage
// took 10 ms instead of 4 on the dam break, llvmpipe).
#define hemo_inflow_sample(block, k) ((block).waveform[(k) >> 2u][(k) & 3u])
// The inflow's ramp at time t, min(t / ramp, 1) (1 without one): of the mean speed, and of a
// pressure inlet's pressure over the background (a macro, as above).
#define hemo_inflow_ramp(block, t) ((block).ramp > 0.0 ? clamp((t) / (block).ramp, 0.0, 1.0) : 1.0)
