// The SPH parameter block (see interface/sph.h for units), bound read-only.
struct SphParams {
  vec4 gravity;
  float h;
  float supportRadius;
  float listRadius;
  float kernelNorm;
  float rho0;
  float taitB;
  float mu;
  float etaSq;
  float psi;
  float repulsionCutoff;
  float wallSpacing;
  float cflAcoustic;
  float cflForce;
  float dtViscous;
  float dtMax;
  float c0;
  uint clampNegativePressure;
  uint neighbourCapacity;
  float dampingRate;
  float dampingUntil;
  uint spsEnabled;
  float spsSmagorinsky;
  float spsBlinn;
  uint listStride;
  vec4 origin;     // xyz: domain origin (m), where periodic axes start
  vec4 period;     // xyz: period (m) on periodic axes, 0 on the others
  vec4 invPeriod;  // xyz: 1 / period, 0 on non-periodic axes
};

// Entry k of particle i's neighbour list. Entries are interleaved (entry k of every particle,
// then entry k + 1), so neighbouring invocations read neighbouring words.
#define hemo_list_slot(i, k) ((k) * params.listStride + (i))

// Minimum-image separation (unchanged on non-periodic axes). Needs `params` bound.
#define hemo_min_image(d) ((d) - params.period.xyz * round((d) * params.invPeriod.xyz))
// Position wrapped into [origin, origin + period) on periodic axes.
#define hemo_wrap_position(x) ((x) - params.period.xyz * floor(((x) - params.origin.xyz) * params.invPeriod.xyz))
