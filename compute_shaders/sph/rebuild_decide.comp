#version 450
// The neighbour list's rebuild decision, one workgroup after the integrator's full stage
// (symplectic Euler, RK2's second; interface/sph.h, "the rebuild test"):
// 1. the reach test: the integrator's partials, one per SIMD group, reduced to
//    (min d.x, max d.x, the two largest reaches); slots the integrator left out (rigid boundary
//    particles, displacement 0) count with reach |c|, the predicted middle. The result keeps
//    the half-sum of the two largest reaches and the middle of this range for the next step's
//    prediction;
// 2. with the tile test (specialization constant 1, symplectic Euler): the largest separation
//    of the displacement boxes of an occupied tile (one with moving particles) and each of its
//    neighbours and itself; the boxes are cleared for the next step. In steps the integrator
//    did not collect them (its last half-sum was small) the bound is +inf and the reach test
//    decides alone;
// 3. the decision, and the neighbour-rebuild gate for the next step (common/gate.glsl):
//      open = reach test fails (half-sum > half the skin, or NaN)
//             and (no tile test, or it fails: a separation > the skin, or the half-sum > origin.w)
//    When the gate opens the result becomes (0, 0, half-sum, 0): the next step rebuilds and
//    displacements restart from the new build.
// The result does not depend on the order of the partials (min and max are exact).
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "common/index.glsl"
#include "common/tiles.glsl"
#include "common/rebuild_test.glsl"

layout(constant_id = 1) const uint kTiles = 1u;

layout(std140, binding = HEMO_DECIDE_BINDING_TILE_GRID) uniform TileGridBlock { TileGrid tiles; };
// A tile's HEMO_TILE_WORDS words as two uvec4: read as texels (llvmpipe loads a storage buffer
// lane by lane and word by word: with seven loads per box and 27 boxes per occupied tile the
// comparison took most of this pass), cleared as stores.
#if HEMO_TILE_WORDS != 8 || HEMO_TILE_STATIC_WORD != 3
#error "the tile boxes are read and cleared as two uvec4 per tile"
#endif
layout(std430, binding = HEMO_DECIDE_BINDING_TILE_BOXES) writeonly buffer TileBoxes { uvec4 tileBox[]; };
layout(binding = HEMO_DECIDE_BINDING_TILE_BOXES_IN) uniform usamplerBuffer tileBoxIn;
layout(std430, binding = HEMO_DECIDE_BINDING_TILE_OCCUPIED) buffer TileOccupied {
  uint tileOccupied;
  uint tilesCollected;  // 0: the integrator did not collect this step (then the tiles cannot decide)
  uint occupiedTiles[];
};
// The last step's result on entry, this step's on exit.
layout(std430, binding = HEMO_DECIDE_BINDING_CHECK_RESULT) buffer Result { vec4 checkResult; };
layout(std430, binding = HEMO_DECIDE_BINDING_TILE_RESULT) writeonly buffer TileResult { float tileResult; };
layout(std430, binding = HEMO_DECIDE_BINDING_GATE_ARMED) readonly buffer GateArmed { uvec4 gateArmed[]; };
layout(std430, binding = HEMO_DECIDE_BINDING_GATE_ARGS) writeonly buffer GateArgs { uvec4 gateArgs[]; };
layout(std430, binding = HEMO_DECIDE_BINDING_GATE_OPENED) buffer GateOpened { uint gateOpened; };
layout(binding = HEMO_DECIDE_BINDING_CHECK_PARTIALS) uniform samplerBuffer partials;
layout(std430, binding = HEMO_DECIDE_BINDING_CHECK_COUNT) readonly buffer PartialCount { uint partialCount; };
layout(std430, binding = HEMO_DECIDE_BINDING_INTEGRATE_ARGS) writeonly buffer IntegrateArgs { uvec4 integrateArgs[2]; };
layout(push_constant) uniform Push {
  float threshold;   // half the skin, m
  uint gateSlots;
  uint staticSlots;  // 1: slots the integrator left out hold rigid boundary particles
  uint groupsX;      // the integrator's workgroups (x, y), for the next step's arguments
  uint groupsY;
} pc;

#include "common/gate.glsl"

// Tile t's box of displacements [lo, hi] (rigid particles: the point 0); false when empty.
bool hemo_tile_box(uint t, out vec3 lo, out vec3 hi) {
  const uvec4 a = texelFetch(tileBoxIn, int(2u * t));       // the largest -d per axis, the static word
  const uvec4 b = texelFetch(tileBoxIn, int(2u * t + 1u));  // the largest d per axis
  const bool moving = b.x != 0u;
  const bool rigid = a.w != 0u;
  lo = vec3(0.0);
  hi = vec3(0.0);
  if (moving) {
    lo = -vec3(hemo_order_value(a.x), hemo_order_value(a.y), hemo_order_value(a.z));
    hi = vec3(hemo_order_value(b.x), hemo_order_value(b.y), hemo_order_value(b.z));
    if (rigid) {
      lo = min(lo, vec3(0.0));
      hi = max(hi, vec3(0.0));
    }
  }
  return moving || rigid;
}

// The largest squared separation of an occupied tile's box and its neighbours' (and its own),
// over this invocation's share of the occupied tiles.
float hemo_tile_worst() {
  const uvec3 n = tiles.count.xyz;
  const uint occupied = min(tileOccupied, n.x * n.y * n.z);
  float worst = 0.0;
  for (uint p = gl_LocalInvocationID.x; p < occupied; p += gl_WorkGroupSize.x) {
    const uint t = occupiedTiles[p];
    vec3 lo, hi;
    hemo_tile_box(t, lo, hi);
    const ivec3 c = ivec3(t % n.x, (t / n.x) % n.y, t / (n.x * n.y));
    // All 27 (two tiles of rigid particles only are never compared, so an occupied tile
    // takes each of its neighbours, occupied or not).
    for (uint k = 0u; k < 27u; ++k) {
      ivec3 o = c + ivec3(int(k % 3u) - 1, int((k / 3u) % 3u) - 1, int(k / 9u) - 1);
      bool inside = true;
      for (int a = 0; a < 3; ++a) {
        if ((tiles.count.w & (1u << a)) != 0u) {
          o[a] = (o[a] + int(n[a])) % int(n[a]);
        } else {
          inside = inside && o[a] >= 0 && o[a] < int(n[a]);
        }
      }
      vec3 lo2, hi2;
      if (inside && hemo_tile_box(hemo_tile_index(uvec3(o), tiles), lo2, hi2)) {
        const vec3 apart = max(hi - lo2, hi2 - lo);
        worst = max(worst, dot(apart, apart));
      }
    }
  }
  return worst;
}

// Clears the occupied tiles' boxes (this invocation's share), keeping each tile's static word
// (and the unused last one).
void hemo_tile_clear() {
  const uvec3 n = tiles.count.xyz;
  const uint occupied = min(tileOccupied, n.x * n.y * n.z);
  for (uint p = gl_LocalInvocationID.x; p < occupied; p += gl_WorkGroupSize.x) {
    const uint t = occupiedTiles[p];
    tileBox[2u * t] = uvec4(0u, 0u, 0u, texelFetch(tileBoxIn, int(2u * t)).w);
    tileBox[2u * t + 1u] = uvec4(0u, 0u, 0u, texelFetch(tileBoxIn, int(2u * t + 1u)).w);
  }
}

shared vec4 s_partial[gl_WorkGroupSize.x];
shared bool s_nan[gl_WorkGroupSize.x];
shared uint s_bound;
shared bool s_open;

bool hemo_decide();

void main() {
  const uint lid = gl_LocalInvocationID.x;
  const float inf = uintBitsToFloat(0x7f800000u);
  vec4 r = vec4(inf, -inf, -inf, -inf);
  bool nan = false;
  const uint count = partialCount;
  for (uint p = lid; p < count; p += gl_WorkGroupSize.x) {
    const vec4 v = texelFetch(partials, int(p));
    nan = nan || any(isnan(v));
    r = hemo_rebuild_combine(r, v);
  }
  s_partial[lid] = r;
  s_nan[lid] = nan;
  if (lid == 0u) {
    s_bound = 0u;
  }
  barrier();
  if (kTiles != 0u) {
    atomicMax(s_bound, floatBitsToUint(hemo_tile_worst()));  // >= 0: the bits order as the values
    barrier();
    hemo_tile_clear();
  }
  // Halving the partials in shared memory (min, max and the two largest: exact in any order).
  for (uint width = gl_WorkGroupSize.x; width > 1u;) {
    const uint upper = (width + 1u) / 2u;
    if (lid < width - upper) {
      s_partial[lid] = hemo_rebuild_combine(s_partial[lid], s_partial[lid + upper]);
      s_nan[lid] = s_nan[lid] || s_nan[lid + upper];
    }
    barrier();
    width = upper;
  }
  if (lid == 0u) {
    s_open = hemo_decide();
  }
  barrier();
  hemo_gate_arm(s_open, pc.gateSlots);
}

// The decision (invocation 0, after the reductions): the result, the tile test's bound and the
// next step's integrator arguments; returns whether the gate opens.
bool hemo_decide() {
  const float inf = uintBitsToFloat(0x7f800000u);
  vec4 total = s_partial[0];
  const bool anyNan = s_nan[0];
  const vec4 last = checkResult;
  if (pc.staticSlots != 0u) {
    // Slots left out (SphSolver::movingSlots): rigid boundary particles, displacement 0, so
    // their reach is |c| (many of them: twice).
    const float c = abs(hemo_predicted_middle_of(last));
    total = hemo_rebuild_combine(total, vec4(0.0, 0.0, c, c));
  }
  // Fewer than two particles: no pair, nothing to rebuild for.
  const float pairReach = anyNan ? uintBitsToFloat(0x7fc00000u) : total.w == -inf ? -inf : 0.5 * (total.z + total.w);
  bool open = hemo_gate_open(pairReach, pc.threshold);
  if (kTiles != 0u) {
    const float bound = tilesCollected != 0u ? sqrt(uintBitsToFloat(s_bound)) : inf;
    // Either test alone shows that the list still holds every pair within the support.
    const bool tilesHold = bound <= 2.0 * pc.threshold && pairReach <= tiles.origin.w;
    open = open && !tilesHold;
    tileResult = bound;
    tileOccupied = 0u;
    tilesCollected = 0u;
  }
  const float lastMiddle = 0.5 * (last.x + last.y);  // the step before's, for the extrapolation
  const vec4 result = open ? vec4(0.0, 0.0, pairReach, 0.0)
                           : anyNan ? vec4(uintBitsToFloat(0x7fc00000u)) : vec4(total.xy, pairReach, lastMiddle);
  checkResult = result;
  if (kTiles != 0u) {
    // Which integrator the next step runs: the one that collects the tile boxes only where the
    // reach test may fail, past HEMO_TILE_COLLECT_FROM of the threshold (or NaN). Collecting
    // cost the dam break's integrator 0.4-0.6 ms a step, and compiled in but skipped under an
    // empty lane mask it still cost about 40% of the pass (llvmpipe runs a branch's body
    // whether or not a lane takes it). A step whose half-sum
    // jumps past the threshold without having collected rebuilds.
    const bool collect = !(result.z <= float(HEMO_TILE_COLLECT_FROM) * pc.threshold);
    const uvec4 run = uvec4(pc.groupsX, pc.groupsY, 1u, 0u);
    const uvec4 skip = uvec4(0u, 1u, 1u, 0u);
    integrateArgs[0] = collect ? run : skip;
    integrateArgs[1] = collect ? skip : run;
  }
  return open;
}
