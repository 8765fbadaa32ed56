// The driven inflow zone of a periodic vessel (hemo/sim/inflow.hpp has the model), bound as a
// uniform buffer (std140; the C++ struct's float[64] is the vec4[16] here, sample k at
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
  // Open ends (hemo/sim/inflow.hpp; open = 0: the periodic vessel above). x planes (m): the
  // inlet plane (= zoneEnd: the buffer [zoneStart, zoneEnd) lies upstream of it), the outlet
  // plane, and the tube's two ends, past which fluid is parked (the outlet buffer lies in
  // [outletPlane, endX)).
  float inletPlane;
  float outletPlane;
  float startX;
  float endX;
  vec4 parking;       // xyz: where parked slots lie (m); w: the spawn's shift upstream (m, the buffer's length)
  float pendingMargin; // m past the inlet plane at which a crosser still owed its image forces the refill (sph/integrate.comp)
  uint open;          // 1: open ends
  uint reserved2;
  uint reserved3;
};

// Sample k of the waveform of the block `block` (a macro: a function taking the struct by
// value copies all of it, waveform included, into per-invocation memory; the integrator's stage
// took 10 ms instead of 4 on the dam break, llvmpipe).
#define hemo_inflow_sample(block, k) ((block).waveform[(k) >> 2u][(k) & 3u])
