#version 450
// Time integration of fluid and wall particles (the stage is specialization constant 2):
//  symplectic Euler ... v += a dt, x += v dt
//  RK2 midpoint ....... stage 1 saves (x0, v0) and moves to x0 + v0 dt/2, v0 + a0 dt/2;
//                       stage 2 (after new forces at the midpoint) sets x = x0 + v dt,
//                       v = v0 + a dt. Only stage 2 advances the clock.
// dt = min(reduced
// per-particle limits, dtMax, endTime - t) read from the GPU (the host never sees dt inside a
// batch). Once the clock reaches endTime, steps change nothing (dt = 0, not counted).
// While t < dampingUntil the velocity is damped (a settling phase for validation scenes).
// Invocation 0 advances the clock (Kahan-compensated float sum) and logs (t, dt).
// A particle that becomes non-finite records the step in the status buffer.
// The full stages also run the neighbour list's rebuild test: every slot's x displacement
// since the list was built and its reach, reduced per SIMD group to partials that
// sph/rebuild_decide.comp reduces to the decision on the next step's grid and list build.
// A fluid particle that starts the step in the inflow zone of a vessel moves along the axis at
// the prescribed velocity instead (hemo/sim/inflow.hpp), in every mode; across the section it
// moves freely (an open end's buffer moves as a whole, across the section too).
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_vote : require
#include "interface/sph.h"
#include "common/index.glsl"
#include "common/sph_params.glsl"
#include "common/clock.glsl"
#include "common/step_dt.glsl"
#include "common/inflow.glsl"
#include "common/tait.glsl"
#include "common/tiles.glsl"
#include "common/rebuild_test.glsl"

layout(std430, binding = HEMO_INTEGRATE_BINDING_POSITIONS) buffer Positions { vec4 positions[]; };
layout(std430, binding = HEMO_INTEGRATE_BINDING_VELOCITIES) buffer Velocities { vec4 velocities[]; };
// The same records as texels, for the reads (each invocation reads its own record before it
// writes it; interface/sph.h).
layout(binding = HEMO_INTEGRATE_BINDING_POSITIONS_IN) uniform samplerBuffer positionsIn;
layout(binding = HEMO_INTEGRATE_BINDING_VELOCITIES_IN) uniform samplerBuffer velocitiesIn;
// Read-only per-particle inputs are uniform texel buffers (interface/sph.h, "texel slots").
layout(binding = HEMO_INTEGRATE_BINDING_ACCEL) uniform samplerBuffer accelT;
#define accel(k) texelFetch(accelT, int(k))
HEMO_SPH_PARAMS_UNIFORM(HEMO_INTEGRATE_BINDING_PARAMS);
// Values every invocation reads at the same address are uniform buffers (common/sph_params.glsl
// says why).
layout(std140, binding = HEMO_INTEGRATE_BINDING_DT) uniform Dt { vec2 dtMinMax; };
// Two clock records: this step reads clocks[in] and invocation 0 writes clocks[1 - in], so no
// invocation can see a half-advanced clock (workgroups run in any order). (Read through a
// uniform binding of the same buffer, the step measured no faster.)
layout(std430, binding = HEMO_INTEGRATE_BINDING_CLOCK) buffer Clock { ClockRecord clocks[2]; };
layout(std430, binding = HEMO_INTEGRATE_BINDING_STATUS) buffer Status { uint status[]; };
layout(std430, binding = HEMO_INTEGRATE_BINDING_LOG) writeonly buffer Log { vec2 stepLog[]; };
layout(std430, binding = HEMO_INTEGRATE_BINDING_SAVED_POS) buffer SavedPos { vec4 savedPos[]; };
layout(std430, binding = HEMO_INTEGRATE_BINDING_SAVED_VEL) buffer SavedVel { vec4 savedVel[]; };
layout(std430, binding = HEMO_INTEGRATE_BINDING_STEP_DT) buffer StepDt { float stepDt; };
layout(binding = HEMO_INTEGRATE_BINDING_POS_AT_BUILD) uniform samplerBuffer posAtBuildT;
// The previous step's rebuild test: (min d.x, max d.x, half-sum of the two largest reaches,
// the middle of the range a step earlier); sph/rebuild_decide.comp writes the next one after
// this pass.
layout(std140, binding = HEMO_INTEGRATE_BINDING_DRIFT_RANGE) uniform DriftRange { vec4 lastCheck; };
// One partial of the rebuild test per SIMD group, and how many this dispatch wrote
// (sph/rebuild_decide.comp reads them).
layout(std430, binding = HEMO_INTEGRATE_BINDING_CHECK_PARTIALS) writeonly buffer Partials { vec4 partials[]; };
layout(std430, binding = HEMO_INTEGRATE_BINDING_CHECK_COUNT) writeonly buffer PartialCount { uint partialCount; };
layout(std140, binding = HEMO_INTEGRATE_BINDING_INFLOW) uniform Inflow { InflowParams inflow; };
#include "common/inflow_speed.glsl"
layout(binding = HEMO_INTEGRATE_BINDING_STATE) uniform samplerBuffer stateT;
// The tile test (symplectic Euler; interface/sph.h): every invocation widens its particle's
// tile's box, and lists the tile when it is the first; sph/rebuild_decide.comp reads them.
layout(std140, binding = HEMO_INTEGRATE_BINDING_TILE_GRID) uniform TileGridBlock { TileGrid tiles; };
layout(std430, binding = HEMO_INTEGRATE_BINDING_TILE_BOXES) buffer TileBoxes { uint tileBox[]; };
// The tiles with moving particles this step: their number, whether this step collected the
// boxes, then their indices.
layout(std430, binding = HEMO_INTEGRATE_BINDING_TILE_OCCUPIED) buffer TileOccupied {
  uint tileOccupied;
  uint tilesCollected;
  uint occupiedTiles[];
};
#define state(k) texelFetch(stateT, int(k))
layout(std430, binding = HEMO_INTEGRATE_BINDING_NORMALS) buffer Normals { vec4 normals[]; };
// Continuity density (sph/density.comp): fluid particles carry their density in normals[i].w.
// 1 (symplectic Euler): the density pass advanced it (state.x); it is stored back for the next
// step. 2 (RK2 midpoint): the stages advance it with the rate in state.z, the first stage
// keeping rho(t) in savedVel.w. 0: summation density, nothing to carry.
layout(constant_id = 1) const uint kContinuity = 0u;
// The stage (HEMO_INTEGRATE_*): a constant, so each pipeline holds only its own stage's code.
// llvmpipe runs the body of a branch under a lane mask even when no lane takes it, and the
// stores of the RK2 stages cost the symplectic step about a third of this pass.
layout(constant_id = 2) const uint kMode = 0u;
// 1: the scene has an inflow zone (common/inflow.glsl); 2: and open ends (below); 0 compiles
// its code out, for llvmpipe runs the body of a branch no lane takes.
layout(constant_id = 3) const uint kInflow = 1u;
// Open ends (kInflow 2; hemo/sim/inflow.hpp): fluid crossing the inlet and outlet planes is
// counted, a particle that leaves a buffer into the lumen is flagged until the refill gives the
// buffer its image, both buffers are driven (a pressure end's from the lumen's speeds next to
// its plane), and fluid past either end of the tube or out of the domain is parked.
layout(std430, binding = HEMO_INTEGRATE_BINDING_OPEN_COUNTERS) buffer OpenCounters { uint openCounters[]; };
layout(std430, binding = HEMO_INTEGRATE_BINDING_PENDING) buffer Pending { uint pending[]; };
// Pressure ends (common/inflow.glsl, HEMO_OPEN_BINS): this step's sums of the axial velocities
// next to each plane, and the profiles the last step's sums gave, which the buffers move at.
layout(std430, binding = HEMO_INTEGRATE_BINDING_OPEN_SUMS) buffer OpenSums { uint openSums[]; };
layout(std430, binding = HEMO_INTEGRATE_BINDING_OPEN_PROFILE) readonly buffer OpenProfile { float openProfile[]; };
layout(std430, binding = HEMO_INTEGRATE_BINDING_ESCAPE_MASK) readonly buffer EscapeMask { uint escapeMask[]; };
// 1: this symplectic-Euler integrator collects the tile boxes (see gCollectTiles).
layout(constant_id = 4) const uint kCollect = 0u;
layout(push_constant) uniform Push {
  uint n;
  uint step;
  uint logIndex;
  float endTime;
  uint clockIn;
  float threshold;     // rebuild when the largest reach exceeds it (half the skin), m
  uint wallAdvanced;   // 1: the wall's substeps (wall/substep.comp) have moved the wall particles
} pc;

// A wall particle whose springs all broke is marked by the wall stage with accel.w < 0 (fluid
// particles keep a positive value there): from now on it has no SPH mass, so the fluid no
// longer sees it. (Written here, not by the wall stage, whose other invocations read the
// positions.)
float hemo_sph_mass(float mass, float accelW) {
  return accelW < 0.0 ? 0.0 : mass;
}

// Fluid and wall particles move (walls with the acceleration of wall/spring_forces.comp);
// rigid boundary particles do not.
bool hemo_moves(float kind) {
  return uint(kind) == HEMO_KIND_FLUID || uint(kind) == HEMO_KIND_WALL;
}

// The rebuild test's inputs (docs/architecture.md, "the rebuild test"): the x displacement
// d.x since the list build, and the reach
//   reach = |d - (c, 0, 0)|,  c = the middle (min d.x + max d.x) / 2 of this step, predicted
//                               linearly from those of the two steps before (2 m1 - m2),
// plus, when the next step evaluates forces at a midpoint (RK2), the farthest the next half
// step can take the particle, |v| min(dtMax, C_a h / (c0 + |v|)) / 2.
// Any vector c common to all slots keeps the test valid: two particles' separation has
// changed by |d_i - d_j| <= |d_i - c| + |d_j - c| <= r1 + r2, the two largest reaches, so
// the list holds every pair within the support while r1 + r2 stays under the skin (the test
// below). Taking c in the middle of the flow's displacements halves the reach of a uniform or parabolic drift along x
// (a vessel's axis), which does not change who neighbours whom. Predicting the middle lets
// this pass compute the reach (no pass of its own); the
// previous step's middle alone lagged the dam break's front by a step's motion, 15% of the
// threshold, and rebuilt the list 30 times in 600 steps against 21. After a rebuild both
// middles restart at 0 (sph/rebuild_decide.comp).
float hemo_predicted_middle() {
  return hemo_predicted_middle_of(lastCheck);
}

// (d.x, reach) of slot i at x, moving at v; its displacement d and position x0 at the build.
vec2 hemo_rebuild_test(uint i, vec3 x, vec3 v, out vec3 d, out vec3 x0) {
  x0 = texelFetch(posAtBuildT, int(i)).xyz;
  d = hemo_min_image(x - x0, hemo_pair_params());
  float r = length(d - vec3(hemo_predicted_middle(), 0.0, 0.0));
  if (kInflow == 2u && pending[i] != 0u) {
    // A crosser of an end's plane whose image the buffer still lacks (it appears at the next
    // rebuild, sph/open_spawn.comp) fails both tests once it is `pendingMargin` past the plane
    // into the lumen: the refill comes before the buffer's gap nears the lumen, in any flow (a
    // plug flow alone would never rebuild the list). (HEMO_OPEN_OWING, HEMO_OPEN_CREDITED: the
    // end it owes an image)
    const uint e = (pending[i] - 1u) % HEMO_OPEN_MAX_ENDS;
    if (hemo_open_local(inflow, e, x).x - inflow.ends[e].origin.w >= inflow.pendingMargin) {
      r = 3.0e38;
    }
  }
  if (kMode == HEMO_INTEGRATE_RK2_FULL) {
    const float speed = length(v);
    r += 0.5 * speed * min(params.dtMax, params.cflAcoustic * params.h / max(params.c0 + speed, 1.0e-30));
  }
  return vec2(d.x, r);
}

// The subgroup's two largest reaches, each invocation holding its own two (t.x >= t.y): the
// largest, and the larger of the other invocations' largest and its holder's second (the
// largest again when two invocations hold it).
vec2 hemo_subgroup_top2(vec2 t) {
  const float first = subgroupMax(t.x);
  const bool holder = t.x == first;
  const float second = subgroupMax(holder ? t.y : t.x);
  return vec2(first, subgroupAdd(holder ? 1u : 0u) > 1u ? first : second);
}

// The tile test (interface/sph.h). Two particles i, j that were more than the list radius R
// apart at the build and are now within the support 2h have closed in by more than the skin:
// |d_i - d_j| > R - 2h. If their build positions lie in neighbouring tiles A, B (or one tile),
// |d_i - d_j| is at most the separation of the tiles' displacement boxes,
// |max(hi_A - lo_B, hi_B - lo_A)| per axis; if not, the tiles are at least a tile apart, so
// the pair has closed in by more than a tile less the support, and the two largest reaches
// sum to more than that. Where the flow carries whole neighbourhoods along (the dam break's
// surge) the boxes stay small while single particles travel far: the reach test alone rebuilt
// the list for displacements common to both particles of every pair.

// Whether this pipeline collects the tile boxes (symplectic Euler, constant 4): the previous
// step's sph/rebuild_decide.comp picks it or the other through their indirect arguments, only
// where the reach test may fail (a step after the host reset the test always collects).
const bool gCollectTiles = kMode == HEMO_INTEGRATE_SYMPLECTIC_EULER && kCollect != 0u;

// Widens tile t's box by [lo, hi]; the first to widen it lists the tile as occupied (the
// list's order varies from run to run, the check's maximum over it does not).
void hemo_tile_widen(uint t, vec3 lo, vec3 hi) {
  const uint b = t * HEMO_TILE_WORDS;
  const uint before = atomicMax(tileBox[b + 4u], hemo_order_key(hi.x));
  atomicMax(tileBox[b + 5u], hemo_order_key(hi.y));
  atomicMax(tileBox[b + 6u], hemo_order_key(hi.z));
  atomicMax(tileBox[b], hemo_order_key(-lo.x));
  atomicMax(tileBox[b + 1u], hemo_order_key(-lo.y));
  atomicMax(tileBox[b + 2u], hemo_order_key(-lo.z));
  if (before == 0u) {
    const uint k = atomicAdd(tileOccupied, 1u);
    if (k < tiles.count.x * tiles.count.y * tiles.count.z) {  // (a NaN's key may be 0: listed twice)
      occupiedTiles[k] = t;
    }
  }
}

// A moving slot's displacement d into the box of the tile of its build position x0. Slots
// next to each other were sorted by cell at the build and mostly share a tile: a SIMD group
// whose lanes all do widens it once (on lavapipe an atomic costs each lane its own). One
// call either way: llvmpipe runs both sides of a branch, the atomics of each included.
void hemo_tile_collect(vec3 x0, vec3 d) {
  const uint t = hemo_tile_index(hemo_tile_cell(x0, tiles), tiles);
  const bool together = subgroupAllEqual(t);
  const vec3 lo = subgroupMin(d), hi = subgroupMax(d);
  if (!together || subgroupElect()) {
    hemo_tile_widen(t, together ? lo : d, together ? hi : d);
  }
}

// The rebuild test's partial, in uniform control flow: each SIMD group (subgroup) reduces its
// slots' (d.x, reach) to (min d.x, max d.x, the two largest reaches), NaN if any lane saw one,
// and one lane stores it; sph/rebuild_decide.comp, one workgroup dispatched after this pass,
// reduces the partials, decides and arms the gate. (Reducing through shared memory in each
// workgroup, with the last one to finish, found with an atomic counter, reducing the partials
// and arming the gate, cost the dam break's step 0.5 ms of this pass's 2.0 on lavapipe: the
// barriers, the counter and the masked tail that llvmpipe runs in every workgroup.)
void hemo_store_rebuild_partial(vec2 test, bool valid) {
  const float inf = uintBitsToFloat(0x7f800000u);
  const bool nan = valid && (isnan(test.x) || isnan(test.y));
  const vec4 m = valid ? vec4(test.x, test.x, test.y, -inf) : vec4(inf, -inf, -inf, -inf);
  const vec4 sub = vec4(subgroupMin(m.x), subgroupMax(m.y), hemo_subgroup_top2(m.zw));
  const bool subNan = subgroupAny(nan);
  if (subgroupElect()) {
    partials[hemo_group_index() * gl_NumSubgroups + gl_SubgroupID] = subNan ? vec4(uintBitsToFloat(0x7fc00000u)) : sub;
  }
  if (hemo_global_index() == 0u) {
    const uint groups = gl_NumWorkGroups.x * gl_NumWorkGroups.y * gl_NumWorkGroups.z;
    partialCount = groups * gl_NumSubgroups;
    tilesCollected = gCollectTiles ? 1u : 0u;
  }
}


// Set by hemo_inflow_driven: the velocity it gives is the particle's whole velocity (a
// pressure end's buffer, which moves as a whole: across the section too, so its particles,
// held at one pressure, cannot crowd), not only its axial one.
bool gWholeVelocity = false;

// Whether x lies in open end e's buffer (s in [0, length) within its reach); l: its (s, r^2).
bool hemo_open_in_buffer(vec3 x, uint e, out vec2 l) {
  l = hemo_open_local(inflow, e, x);
  const float reach = inflow.ends[e].shift.w;
  return l.x >= 0.0 && l.x < inflow.ends[e].origin.w && l.y < reach * reach;
}

// True when a fluid particle at x (start of the step) is in the inflow zone (open ends: in
// any end's buffer); u: its velocity (the periodic zone: its axial part, along x; an open end's
// buffer: the whole of it, gWholeVelocity), s2: its (r / R)^2.
bool hemo_inflow_driven(vec3 x, float kind, float time, out vec3 u, out float s2) {
  u = vec3(0.0);
  s2 = 0.0;
  if (kInflow == 0u || inflow.enabled == 0u || uint(kind) != HEMO_KIND_FLUID) {
    return false;
  }
  if (kInflow == 2u) {
    // Open ends (hemo/sim/inflow.hpp): every particle in a buffer is driven, as a whole (its
    // velocity, not only its axial part), at rest beyond the radius, so none drifts out
    // through the end or back into the lumen along the wall.
    vec2 l;
    uint e = 0u;
    while (e < inflow.endCount && !hemo_open_in_buffer(x, e, l)) {
      ++e;
    }
    if (e == inflow.endCount) {
      return false;
    }
    const float R = inflow.ends[e].axis.w;
    s2 = l.y / (R * R);
    float inward;  // m/s along the end's axis, into the lumen
    if (inflow.ends[e].drive.z != 0.0) {
      // A pressure end: the lumen's speed along the axis next to the plane at this radius (a
      // zero gradient), plus what the lumen's pressure there lacks of the end's, or less what
      // it exceeds it by, over rho0 c0 (sph/open_profile.comp: the outgoing characteristic;
      // without it a lumen at rest between two buffers at rest never starts to flow).
      const float lumen = openProfile[HEMO_OPEN_PRESSURE(e)];
      const float end = hemo_background_pressure(time, params) + hemo_open_end_pressure(e, time);
      const float lack = lumen > 0.5 * HEMO_OPEN_NO_PRESSURE ? end - lumen : 0.0;  // Pa: the end's pressure over the lumen's
      inward = s2 < 1.0 ? openProfile[e * HEMO_OPEN_BINS + hemo_open_bin(s2)] + lack * inflow.slab.y : 0.0;
      // At most the speed the end's whole pressure gives the blood, sqrt(2 p / rho0) (Bernoulli):
      // where the lumen cannot hold a pressure (a torn vessel drains through its tear) the
      // characteristic term would add to the lumen's speed, which the buffer itself drives, step
      // after step (a torn aneurysm's outlet buffer reached 11 m/s).
      const float fastest = sqrt(2.0 * max(end, lumen) / params.rho0);
      inward = clamp(inward, -fastest, fastest);
    } else {
      // The inflow's profile; at the outlet, the same flow rate out of the lumen. The buffer
      // moves as a whole, across the section too (its images, copies of the lumen's crossers,
      // keep their spacing): free across the section, the buffer's particles next to its cut
      // far end and its images landing among them were knocked sideways at up to twice the
      // inflow's peak speed, and the inlet delivered 7% less than its profile carries.
      const float profile = inflow.profile == 1u ? (s2 < 1.0 ? 1.0 : 0.0) : 2.0 * max(1.0 - s2, 0.0);
      const float speed = hemo_inflow_mean_speed(time) * profile * inflow.ends[e].drive.x;
      inward = e == 0u ? speed : -speed;
    }
    gWholeVelocity = true;
    u = inward * inflow.ends[e].axis.xyz;
    return true;
  }
  if (!(x.x >= inflow.zoneStart && x.x < inflow.zoneEnd)) {
    return false;
  }
  const vec2 d = x.yz - vec2(inflow.centreY, inflow.centreZ);
  s2 = dot(d, d) / (inflow.radius * inflow.radius);
  if (s2 >= 1.0) {
    return false;  // outside the lumen (escaped blood is never driven)
  }
  const float profile = inflow.profile == 1u ? (s2 < 1.0 ? 1.0 : 0.0) : 2.0 * max(1.0 - s2, 0.0);
  u = vec3(hemo_inflow_mean_speed(time) * profile, 0.0, 0.0);
  return true;
}

// Adds a value to bin `bin` of the open ends' sums in fixed point (value + offset) scale
// (common/inflow.glsl): the low word, a carry into the high word where it wrapped, the count.
void hemo_open_sum(uint bin, float value, float offset, float scale) {
  const uint word = bin * HEMO_OPEN_SUM_WORDS;
  const uint add = uint(clamp((value + offset) * scale, 0.0, 4294967040.0));
  const uint before = atomicAdd(openSums[word], add);
  if (before + add < before) {
    atomicAdd(openSums[word + 1u], 1u);
  }
  atomicAdd(openSums[word + 2u], 1u);
}

// Slot i has left end e's buffer into the lumen: it owes the buffer its image
// (HEMO_OPEN_OWING), or, holding a credit for it (normals.w = e + 1), spends it
// (HEMO_OPEN_CREDITED: its image is made only where the buffer has lost particles at its far
// end since, sph/open_spawn.comp).
void hemo_open_leave_buffer(uint i, uint e) {
  if (normals[i].w == float(e + 1u)) {
    normals[i].w = 0.0;
    pending[i] = HEMO_OPEN_CREDITED(e);
  } else {
    pending[i] = HEMO_OPEN_OWING(e);
  }
}

// Slot i has come into end e's buffer from the lumen: it cancels the image it owes the buffer
// (and gets back the credit it had spent on it), or earns a credit for it.
void hemo_open_enter_buffer(uint i, uint e) {
  if (pending[i] == HEMO_OPEN_OWING(e)) {
    pending[i] = 0u;
  } else {
    pending[i] = pending[i] == HEMO_OPEN_CREDITED(e) ? 0u : pending[i];
    normals[i].w = float(e + 1u);
  }
}

// Whether x lies in a cell of the escape mask (common/inflow.glsl): blood far outside the wall.
bool hemo_open_escaped(vec3 x) {
  if (inflow.escapeDims.w == 0u) {
    return false;
  }
  const vec3 f = floor((x - inflow.escapeOrigin.xyz) * inflow.escapeOrigin.w);
  if (any(lessThan(f, vec3(0.0))) || any(greaterThanEqual(f, vec3(inflow.escapeDims.xyz)))) {
    return false;  // (outside the domain: the box parks it)
  }
  const uvec3 c = uvec3(f);
  const uint k = c.x + inflow.escapeDims.x * (c.y + inflow.escapeDims.y * c.z);
  return (escapeMask[k >> 5u] & (1u << (k & 31u))) != 0u;
}

// Open ends (kInflow 2), after the update of fluid slot i from `start` to x: the plane
// crossings, and parking past an end or outside the domain.
void hemo_open_ends(uint i, vec3 start, inout vec4 x, inout vec4 v) {
  // The lumen's speeds along each end's axis in the slab next to its plane, by radius, for the
  // pressure ends' buffers (their zero gradient along the axis), and its pressure there (every
  // buffer's: sph/density.comp, and the pressure ends' characteristic term).
  for (uint e = 0u; e < inflow.endCount; ++e) {
    const vec2 l = hemo_open_local(inflow, e, x.xyz);
    const float R = inflow.ends[e].axis.w;
    const float s2 = l.y / (R * R);
    const float into = l.x - inflow.ends[e].origin.w;  // m past the plane into the lumen
    if (s2 < 1.0 && into >= 0.0 && into < inflow.slab.x) {
      hemo_open_sum(e * HEMO_OPEN_BINS + hemo_open_bin(s2), dot(v.xyz, inflow.ends[e].axis.xyz), HEMO_OPEN_SPEED_OFFSET,
                    HEMO_OPEN_FIXED_SCALE);
      hemo_open_sum(HEMO_OPEN_PRESSURE(e), state(i).y, HEMO_OPEN_PRESSURE_OFFSET, HEMO_OPEN_PRESSURE_SCALE);
      break;
    }
  }
  // Each buffer holds the same particles whatever crosses its plane. A particle that leaves a
  // buffer into the lumen owes the buffer its image at the buffer's far end (HEMO_OPEN_OWING;
  // a buffer length back along the end's axis: the inflow at the inlet, reverse flow at an
  // outlet); one that comes back into the buffer cancels the image it still owes, or else
  // earns a credit (normals.w = e + 1: fluid particles carry no normal, and open ends use
  // summation density) that its next crossing into the lumen spends: its image is then made
  // only as far as the buffer has lost particles past its far end meanwhile
  // (HEMO_OPEN_CREDITED; sph/open_spawn.comp counts each buffer's deficit). (Near the wall,
  // where the flow is slow, particles cross back and forth: each forward crossing made an
  // image, and the buffer filled up. Without the deficit, a buffer that reverse flow had
  // emptied at its far end got nothing back when the flow turned.)
  uint parkedBy = HEMO_OPEN_MAX_ENDS;  // the end past which the particle lies (none)
  for (uint e = 0u; e < inflow.endCount; ++e) {
    const vec2 l = hemo_open_local(inflow, e, x.xyz);
    const float reach = inflow.ends[e].shift.w;
    const float plane = inflow.ends[e].origin.w;
    const bool near = l.y < reach * reach;
    const float before = hemo_open_local(inflow, e, start).x;
    // (the inlet's crossings into the lumen are the inflow; an outlet's out of it its outflow)
    if (near && before < plane && l.x >= plane) {
      atomicAdd(openCounters[HEMO_OPEN_COUNTER_LEAVE(e)], 1u);
      hemo_open_leave_buffer(i, e);
    } else if (near && before >= plane && l.x < plane) {
      atomicAdd(openCounters[HEMO_OPEN_COUNTER_ENTER(e)], 1u);
      hemo_open_enter_buffer(i, e);
    }
    if (parkedBy == HEMO_OPEN_MAX_ENDS && near && l.x < 0.0 && l.x >= -reach) {
      parkedBy = e;
    }
  }
  // Blood that has left the domain (through a tear), or lies in a cell of the escape mask (far
  // enough outside the wall), is parked too, and counted.
  const bool outside = any(lessThan(x.xyz, inflow.boxMin.xyz)) || any(greaterThan(x.xyz, inflow.boxMax.xyz)) ||
                       hemo_open_escaped(x.xyz);
  if (parkedBy < HEMO_OPEN_MAX_ENDS || outside) {
    atomicAdd(openCounters[parkedBy < HEMO_OPEN_MAX_ENDS ? HEMO_OPEN_COUNTER_PARKED(parkedBy) : HEMO_OPEN_COUNTER_PARKED_OUTSIDE], 1u);
    pending[i] = 0u;  // (the image would be taken from the parking point)
    x.xyz = inflow.parking.xyz;
    v = vec4(0.0, 0.0, 0.0, float(HEMO_KIND_PARKED));
  }
}

// The full stages' update of slot i (< n); returns its rebuild test (d.x, reach).
vec2 hemo_advance(uint i, ClockRecord clock, float dt, bool running, out vec3 d, out vec3 x0) {
  vec4 v = texelFetch(velocitiesIn, int(i));
  vec4 x = texelFetch(positionsIn, int(i));
  if (!running || !hemo_moves(v.w)) {
    return hemo_rebuild_test(i, x.xyz, v.xyz, d, x0);
  }
  if (pc.wallAdvanced != 0u && uint(v.w) == HEMO_KIND_WALL) {
    // Already at the end of the step: only the blow-up check and the detachment mark.
    if (any(isnan(x.xyz)) || any(isinf(x.xyz)) || any(isnan(v.xyz)) || any(isinf(v.xyz))) {
      atomicMin(status[HEMO_STATUS_FIRST_BAD_STEP], pc.step);
      atomicAdd(status[HEMO_STATUS_NONFINITE], 1u);
    }
    positions[i].w = hemo_sph_mass(x.w, accel(i).w);
    return hemo_rebuild_test(i, x.xyz, v.xyz, d, x0);
  }
  // Where the step started (the inflow zone is judged there).
  const vec3 start = kMode == HEMO_INTEGRATE_RK2_FULL ? savedPos[i].xyz : x.xyz;
  if (kMode == HEMO_INTEGRATE_RK2_FULL) {
    // midpoint rule: x1 = x0 + dt v(mid), v1 = v0 + dt a(mid)
    const vec4 v0 = savedVel[i];
    x.xyz = savedPos[i].xyz + v.xyz * dt;  // wrapped below: the saved position may be across the seam
    v.xyz = v0.xyz + accel(i).xyz * dt;
  } else {
    v.xyz += accel(i).xyz * dt;
  }
  if (clock.time < params.dampingUntil) {
    v.xyz /= 1.0 + params.dampingRate * dt;  // settling phase only (implicit, so never unstable)
  }
  vec3 u;
  float s2;
  if (hemo_inflow_driven(start, v.w, clock.time - clock.compensation, u, s2)) {
    // The periodic zone's axial velocity is prescribed; the motion across the section stays
    // free, so particles that enter the zone too close can still part (a fully kinematic zone
    // froze such pairs together: 6-13 kPa at its far end and an emptied slice after it). An
    // open end's buffer moves as a whole (gWholeVelocity).
    if (gWholeVelocity) {
      v.xyz = u;
      x.xyz = start + u * dt;
    } else {
      v.x = u.x;
      if (kMode == HEMO_INTEGRATE_RK2_FULL) {
        x.x = start.x + u.x * dt;  // across the section: the midpoint rule as everywhere
      } else {
        x.xyz += v.xyz * dt;
      }
    }
    if (inflow.holdPressure != 0u) {
      // The lumen's supply: the mass moves a tenth of the way each step towards the one that
      // brings the density (of this step's last density pass) to rho0, between the initial
      // mass and the cap. Both ways, so the scatter of single densities does not ratchet the
      // mass up; a tenth, because every zone particle adjusts at once and the full step
      // overshoots on particle-scale patterns (measured: the zone ended 4% dense).
      // Only away from the wall (r < R - dp): next to it the summed density reads low (the
      // wall's two layers do not fill the kernel's support), and the outer ring took up to
      // 2.6 times its mass while the zone's middle ended 7% dense.
      const float inner = 1.0 - params.wallSpacing / inflow.radius;  // R - dp, over R
      const float rho = state(i).x;
      if (rho > 0.0 && s2 < inner * inner) {
        // (per unit of time: a tenth per acoustic step C_a h / c0, WCSPH's own; DFSPH's
        // longer steps take the same fraction of the way per second, at most half)
        const float c0 = sqrt(7.0 * params.taitB / params.rho0);
        const float rate = params.pressureSolver != 0u ? min(0.1 * dt * c0 / (params.cflAcoustic * params.h), 0.5) : 0.1;
        x.w = clamp(x.w * (1.0 + rate * (inflow.restDensity / rho - 1.0)), inflow.baseMass, inflow.maxMass);
      }
    }
  } else if (kMode != HEMO_INTEGRATE_RK2_FULL) {
    x.xyz += v.xyz * dt;
  }
  if (kInflow == 2u && uint(v.w) == HEMO_KIND_FLUID) {
    hemo_open_ends(i, start, x, v);
  }
  x.xyz = hemo_wrap_position(x.xyz);
  if (any(isnan(x.xyz)) || any(isinf(x.xyz)) || any(isnan(v.xyz)) || any(isinf(v.xyz))) {
    atomicMin(status[HEMO_STATUS_FIRST_BAD_STEP], pc.step);
    atomicAdd(status[HEMO_STATUS_NONFINITE], 1u);
  }
  if (kContinuity != 0u && uint(v.w) == HEMO_KIND_FLUID) {
    // (non-finite densities show in the next force pass's blow-up diagnosis)
    normals[i].w = kContinuity == 1u ? state(i).x : savedVel[i].w + state(i).z * dt;
  }
  velocities[i] = v;
  x.w = hemo_sph_mass(x.w, accel(i).w);
  positions[i] = x;
  return hemo_rebuild_test(i, x.xyz, v.xyz, d, x0);
}

void main() {
  const uint i = hemo_global_index();
  const ClockRecord clock = clocks[pc.clockIn];
  // The step's dt: from the reduction (Euler, RK2 first stage), or the one the first stage
  // stored (RK2 second stage, so both stages use the same dt).
  float dt;
  if (kMode == HEMO_INTEGRATE_RK2_FULL) {
    dt = stepDt;
  } else {
    dt = hemo_step_dt(clock, pc.endTime, dtMinMax.x, params.dtMax);
  }
  const bool running = dt > 0.0 || isnan(dt);  // false once the end time is reached
  if (kMode == HEMO_INTEGRATE_RK2_HALF) {
    if (i == 0u) {
      stepDt = dt;  // read by the second stage (a later dispatch)
    }
    if (running && i < pc.n && hemo_moves(texelFetch(velocitiesIn, int(i)).w)) {
      const vec4 v = texelFetch(velocitiesIn, int(i));
      const vec4 x = texelFetch(positionsIn, int(i));
      savedPos[i] = x;
      savedVel[i] = v;
      if (kContinuity == 2u && uint(v.w) == HEMO_KIND_FLUID) {
        const float rho = hemo_carried_density(normals[i].w, params.rho0);
        savedVel[i].w = rho;  // the second stage reads only savedVel.xyz as a velocity
        normals[i].w = rho + state(i).z * (0.5 * dt);
      }
      const vec4 a = accel(i);
      vec3 vMid = v.xyz + a.xyz * (0.5 * dt);
      vec3 drift = v.xyz;
      vec3 u;
      float s2;
      if (hemo_inflow_driven(x.xyz, v.w, clock.time - clock.compensation, u, s2)) {
        if (gWholeVelocity) {
          vMid = u;
          drift = u;
        } else {
          vMid.x = u.x;
          drift.x = u.x;
        }
      }
      velocities[i] = vec4(vMid, v.w);
      positions[i] = vec4(hemo_wrap_position(x.xyz + drift * (0.5 * dt)), hemo_sph_mass(x.w, a.w));
    }
    return;
  }
  if (i == 0u) {
    ClockRecord next = clock;
    if (running) {
      const float y = dt - clock.compensation;
      next.time = clock.time + y;
      next.compensation = (next.time - clock.time) - y;
      next.lastDt = dt;
      next.steps = clock.steps + 1u;
    }
    clocks[1u - pc.clockIn] = next;
    stepLog[pc.logIndex] = vec2(next.time, running ? dt : 0.0);
  }
  bool valid = i < pc.n;
  vec2 test = vec2(0.0);
  if (valid) {
    vec3 d, x0;
    test = hemo_advance(i, clock, dt, running, d, x0);
    if (kInflow == 2u && uint(velocities[i].w) == HEMO_KIND_PARKED) {
      // A parked slot needs no list: it is left out of the test (the jump to the parking
      // point would rebuild the list for nothing).
      valid = false;
      d = vec3(0.0);
      test = vec2(0.0);
    }
    if (gCollectTiles) {
      hemo_tile_collect(x0, d);
    }
  }
  hemo_store_rebuild_partial(test, valid);  // every invocation: subgroup operations
}
