// The SPH parameter block (see interface/sph.h for units), bound as a uniform buffer (its
// layout is the same under std140 and std430: scalars and vec4 only, 304 bytes).
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
  float backgroundPressure;  // Pa, added to the Tait pressure once ramped up
  float backgroundRamp;      // s, linear ramp of the background pressure from t = 0 (0: none)
  uint listParticleStride;
  float deltaSph;  // delta of the continuity density's diffusion term
  vec4 gravityOnly;  // xyz: gravity without the body force (m/s^2)
  uint listPageMask;  // the list's pages (interface/sph.h): a slot's index in its page is slot & mask
  uint pressureSolver;  // 0: Tait equation of state (WCSPH); 1: DFSPH's solve (interface/sph.h)
  float solveFloor;  // DFSPH: the least denominator of the stiffness (kg^2 m^-8; interface/sph.h)
  float rheologyExponent;  // non-Newtonian blood: (n - 1) / a (interface/sph.h, "Viscosity")
  // The neighbour grid (common/grid.glsl, HemoGrid; dims.w unused), for the cell walks
  // (common/cell_walk.glsl).
  vec4 gridOrigin;
  vec4 gridInvCell;
  uvec4 gridDims;
  uvec4 gridPeriodic;
  vec4 carreau;  // non-Newtonian blood: (mu_inf, mu_0 - mu_inf, lambda, a) (interface/sph.h, "Viscosity")
  float solveCompliance;  // DFSPH: the density solve's compliance 1 / c0^2 (s^2 m^-2; interface/sph.h)
  float solvePad0;
  float solvePad1;
  float solvePad2;
};

// Declares `params` at a binding slot. A uniform buffer, not a storage buffer: llvmpipe reads a
// uniform-buffer value once for all lanes, but a storage-buffer load lane by lane even when
// every lane reads the same address, 0.4 against 15 ns per invocation and vec4 read
// (hemo-bench primitives, param_read; docs/benchmarks.md). The host declares the slot uniform
// (PipelineDesc::uniformSlots).
#define HEMO_SPH_PARAMS_UNIFORM(slot) layout(std140, binding = slot) uniform Params { SphParams params; }

// The parameters the neighbour loops use, read once into registers: llvmpipe did not hoist
// the block's loads out of a loop, and reloading them for every pair cost 35-50% of the force
// pass (dam break, measured while the block was a storage buffer).
struct HemoPairParams {
  float h;
  float kernelNorm;
  float support2;    // (2h)^2, m^2
  uint listStride;   // entry k of particle i's list is at
  uint listParticleStride;  // (i & listPageMask) * listParticleStride + k * listStride in i's page
  uint listPageMask;        // (interface/sph.h)
  vec3 period;       // m on periodic axes, 0 on the others
  vec3 invPeriod;    // 1 / period, 0 on bounded axes
};

// Where the shader has bound `params` (a macro, since the buffer is declared after this file).
#define hemo_pair_params()                                                                          \
  HemoPairParams(params.h, params.kernelNorm, params.supportRadius * params.supportRadius, params.listStride, \
                 params.listParticleStride, params.listPageMask,                                     \
                 params.period.xyz, params.invPeriod.xyz)

// Entry k of slot i's list, in the buffer of i's page (the page the dispatch binds).
uint hemo_list_slot(uint i, uint k, HemoPairParams pp) {
  return (i & pp.listPageMask) * pp.listParticleStride + k * pp.listStride;
}

// A list read four entries per texel. With the contiguous layout and a capacity that is a
// multiple of 4 (listParticleStride % 4 == 0), entries k .. k+3 of particle i, k a multiple of
// 4, are one RGBA32UI texel of the list's buffer; a pass with specialization constant
// kListWidth = 4 binds the list in that format and walks it a texel at a time. On lavapipe a
// one-component texel fetch is a hardware gather (vpgatherdd), the costliest instruction of
// the pair loops (perf record of the dam break); a four-component fetch is eight plain
// loads, once per four entries. The interleaved layout (GPUs) reads one entry per texel.
// Entries past the count in the last texel are not valid: the passes substitute the particle
// itself (a pair at zero distance, which adds exactly nothing to a force sum) or skip them.
uint hemo_list_texel(uint i, uint k, HemoPairParams pp) {
  return hemo_list_slot(i, k, pp) >> 2u;
}

// Entries k .. k+3 of slot i's list in LIST (a usamplerBuffer), k < end: one texel when the
// pass reads four entries per texel (kListWidth = 4, k a multiple of 4), else four one-entry
// loads (the interleaved layout; entries from `end` on read entry end - 1, which the caller
// replaces by its padding). Every pass walks its list four entries at a time either way: the
// four loads, and the position loads of the four pairs, are independent and can be in flight
// together. A GPU thread that walked its list one entry at a time waited for each load in turn,
// which at small particle counts (too few threads to hide the wait) set the pass's time.
// A macro: the passes declare kListWidth after including this file.
#define hemo_list_quad(LIST, I, K, END, PP)                                                        \
  (kListWidth == 4u ? texelFetch(LIST, int(hemo_list_texel(I, K, PP)))                             \
                    : uvec4(texelFetch(LIST, int(hemo_list_slot(I, K, PP))).x,                     \
                            texelFetch(LIST, int(hemo_list_slot(I, min((K) + 1u, (END) - 1u), PP))).x, \
                            texelFetch(LIST, int(hemo_list_slot(I, min((K) + 2u, (END) - 1u), PP))).x, \
                            texelFetch(LIST, int(hemo_list_slot(I, min((K) + 3u, (END) - 1u), PP))).x))

// The interacting-pair counts of interface/sph.h: (fluid pairs, boundary pairs).
uvec2 hemo_pair_counts(uint packed) {
  return uvec2(packed & 0xffffu, packed >> 16u);
}

// The range squared (m^2) within which a list entry is an interacting pair (sph/density.comp):
// the support, or the repulsion's reach (its cutoff D plus a wall spacing normal to the wall,
// and a wall spacing along it) where that is larger.
#define hemo_pair_keep2(pp)                                                                         \
  max((pp).support2, (abs(params.repulsionCutoff) + params.wallSpacing) * (abs(params.repulsionCutoff) + params.wallSpacing) + \
                         params.wallSpacing * params.wallSpacing)

// Specialization constant HEMO_SPEC_PERIODIC_AXES (interface/sph.h) of the passes that
// include this file: the periodic axes, bit a for axis a. The pair loops take the minimum
// image on those axes only, so a bounded axis costs nothing per pair; the default, all three,
// gives the same separations (on a bounded axis the period and its reciprocal are 0).
layout(constant_id = HEMO_SPEC_PERIODIC_AXES) const uint kPeriodicAxes = 7u;

// Minimum-image separation (unchanged on non-periodic axes).
vec3 hemo_min_image(vec3 d, HemoPairParams pp) {
  vec3 r = d;
  if ((kPeriodicAxes & 1u) != 0u) r.x = d.x - pp.period.x * round(d.x * pp.invPeriod.x);
  if ((kPeriodicAxes & 2u) != 0u) r.y = d.y - pp.period.y * round(d.y * pp.invPeriod.y);
  if ((kPeriodicAxes & 4u) != 0u) r.z = d.z - pp.period.z * round(d.z * pp.invPeriod.z);
  return r;
}

// Position wrapped into [origin, origin + period) on periodic axes (needs `params` bound).
#define hemo_wrap_position(x) ((x) - params.period.xyz * floor(((x) - params.origin.xyz) * params.invPeriod.xyz))

// A fluid particle's carried density under continuity density, from what normals[i].w holds
// (interface/sph.h): 0 means never advanced, the fill's rest density.
float hemo_carried_density(float stored, float rho0) {
  return stored > 0.0 ? stored : rho0;
}
