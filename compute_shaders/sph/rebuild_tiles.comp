#version 450
// The tile test's comparison (interface/sph.h, "the tile test"), one workgroup after the
// symplectic integrator: the largest separation of the displacement boxes of an occupied tile
// (one with moving particles) and each of its neighbours and itself; then the decision and
// the neighbour-rebuild gate for the next step (common/gate.glsl), and the boxes cleared.
// In steps the integrator did not collect the boxes (its last half-sum was small) the bound
// is +inf: the reach test decides alone.
//   open = reach test fails (half-sum of the two largest reaches > half the skin, or NaN)
//          and tile test fails (a separation > the skin, or the half-sum > origin.w)
// When the gate opens the result becomes (0, 0, half-sum, 0), as the integrator writes it for
// RK2: the next step rebuilds and displacements restart from the new build.
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "common/index.glsl"
#include "common/tiles.glsl"

layout(std140, binding = HEMO_RTILES_BINDING_TILE_GRID) uniform TileGridBlock { TileGrid tiles; };
layout(std430, binding = HEMO_RTILES_BINDING_TILE_BOXES) buffer TileBoxes { uint tileBox[]; };
layout(std430, binding = HEMO_RTILES_BINDING_TILE_OCCUPIED) buffer TileOccupied {
  uint tileOccupied;
  uint tilesCollected;  // 0: the integrator did not collect this step (then the tiles cannot decide)
  uint occupiedTiles[];
};
layout(std430, binding = HEMO_RTILES_BINDING_CHECK_RESULT) buffer Result { vec4 checkResult; };
layout(std430, binding = HEMO_RTILES_BINDING_TILE_RESULT) writeonly buffer TileResult { float tileResult; };
layout(std430, binding = HEMO_RTILES_BINDING_GATE_ARMED) readonly buffer GateArmed { uvec4 gateArmed[]; };
layout(std430, binding = HEMO_RTILES_BINDING_GATE_ARGS) writeonly buffer GateArgs { uvec4 gateArgs[]; };
layout(std430, binding = HEMO_RTILES_BINDING_GATE_OPENED) buffer GateOpened { uint gateOpened; };
layout(push_constant) uniform Push {
  float threshold;  // half the skin, m
  uint gateSlots;
} pc;

#include "common/gate.glsl"

// Tile t's box of displacements [lo, hi] (rigid particles: the point 0); false when empty.
bool hemo_tile_box(uint t, out vec3 lo, out vec3 hi) {
  const uint b = t * HEMO_TILE_WORDS;
  const bool moving = tileBox[b + 4u] != 0u;
  const bool rigid = tileBox[b + HEMO_TILE_STATIC_WORD] != 0u;
  lo = vec3(0.0);
  hi = vec3(0.0);
  if (moving) {
    lo = -vec3(hemo_order_value(tileBox[b]), hemo_order_value(tileBox[b + 1u]), hemo_order_value(tileBox[b + 2u]));
    hi = vec3(hemo_order_value(tileBox[b + 4u]), hemo_order_value(tileBox[b + 5u]), hemo_order_value(tileBox[b + 6u]));
    if (rigid) {
      lo = min(lo, vec3(0.0));
      hi = max(hi, vec3(0.0));
    }
  }
  return moving || rigid;
}

shared uint s_bound;

void main() {
  if (gl_LocalInvocationID.x == 0u) {
    s_bound = 0u;
  }
  barrier();
  const uvec3 n = tiles.count.xyz;
  const uint total = n.x * n.y * n.z;
  const uint occupied = min(tileOccupied, total);
  float worst = 0.0;  // squared
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
  atomicMax(s_bound, floatBitsToUint(worst));  // >= 0: the bits order as the values
  barrier();
  for (uint p = gl_LocalInvocationID.x; p < occupied; p += gl_WorkGroupSize.x) {
    const uint b = occupiedTiles[p] * HEMO_TILE_WORDS;
    tileBox[b] = 0u;
    tileBox[b + 1u] = 0u;
    tileBox[b + 2u] = 0u;
    tileBox[b + 4u] = 0u;
    tileBox[b + 5u] = 0u;
    tileBox[b + 6u] = 0u;
  }
  barrier();
  if (gl_LocalInvocationID.x == 0u) {
    tileOccupied = 0u;
    const float bound = tilesCollected != 0u ? sqrt(uintBitsToFloat(s_bound)) : uintBitsToFloat(0x7f800000u);
    tilesCollected = 0u;
    const float pairReach = checkResult.z;
    // Either test alone shows that the list still holds every pair within the support.
    const bool tilesHold = bound <= 2.0 * pc.threshold && pairReach <= tiles.origin.w;
    const bool open = hemo_gate_open(pairReach, pc.threshold) && !tilesHold;
    if (open) {
      checkResult = vec4(0.0, 0.0, pairReach, 0.0);
    }
    tileResult = bound;
    hemo_gate_arm(open, pc.gateSlots);
  }
}
