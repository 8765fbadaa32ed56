#version 450
// The open ends' refill (interface/sph.h, HEMO_SPAWN_*; hemo/sim/inflow.hpp): at the start
// of every step that rebuilds the neighbour list, fluid particles that left a buffer into the
// lumen since the last refill get their images one buffer length back along the end's axis,
// at the buffer's far end, in parked slots, so the buffer holds as many particles as it
// started with (the image of a periodic seam, made without one): each end makes as many
// images as its buffer's deficit, which its counters give exactly, for its owing crossers
// first and then for those that spent a credit. Three modes over the fluid's slots, with the
// scan of the flags between FLAGS and SCATTER (gpu::PrefixScan): the k-th served crosser takes
// the k-th parked slot in slot order, so the outcome does not depend on the order the
// invocations run in. Run before the grid's build, which sorts the new particles into the
// list.
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "common/index.glsl"
#include "common/inflow.glsl"

layout(std430, binding = HEMO_SPAWN_BINDING_POSITIONS) buffer Positions { vec4 positions[]; };
layout(std430, binding = HEMO_SPAWN_BINDING_VELOCITIES) buffer Velocities { vec4 velocities[]; };
layout(std430, binding = HEMO_SPAWN_BINDING_NORMALS) buffer Normals { vec4 normals[]; };
layout(std430, binding = HEMO_SPAWN_BINDING_PENDING) buffer Pending { uint pending[]; };
layout(std430, binding = HEMO_SPAWN_BINDING_SCAN) buffer Scan { uint scan[]; };
layout(std430, binding = HEMO_SPAWN_BINDING_CROSSERS) buffer Crossers { uint crossers[]; };
layout(std140, binding = HEMO_SPAWN_BINDING_INFLOW) uniform Inflow { InflowParams inflow; };
layout(std430, binding = HEMO_SPAWN_BINDING_COUNTERS) buffer Counters { uint counters[]; };
layout(std430, binding = HEMO_SPAWN_BINDING_STATUS) buffer Status { uint status[]; };
layout(push_constant) uniform Push {
  uint n;     // fluid slots N
  uint mode;  // HEMO_SPAWN_*
} pc;

// The flag segment of pending value c (interface/sph.h: HEMO_OPEN_OWING, HEMO_OPEN_CREDITED)
// among E ends: owing e -> e, credited e -> E + e; the parked slots' (c = 0) is 2E.
uint hemo_spawn_segment(uint c, uint ends) {
  if (c == 0u) {
    return 2u * ends;
  }
  return c <= HEMO_OPEN_MAX_ENDS ? c - 1u : ends + c - 1u - HEMO_OPEN_MAX_ENDS;
}

// How many crossers of segment `seg` (< 2E) are served, from the scan: each end serves its
// owing crossers first, then those that spent a credit, up to its deficit.
uint hemo_spawn_served(uint seg, uint n, uint ends) {
  const uint e = seg < ends ? seg : seg - ends;
  const uint deficit = scan[(2u * ends + 1u) * n + 1u + e];
  const uint owing = scan[(e + 1u) * n] - scan[e * n];
  const uint owingServed = min(deficit, owing);
  if (seg < ends) {
    return owingServed;
  }
  return min(deficit - owingServed, scan[(seg + 1u) * n] - scan[seg * n]);
}

// Where segment `seg`'s served crossers start in the served order (the segments in order).
uint hemo_spawn_offset(uint seg, uint n, uint ends) {
  uint offset = 0u;
  for (uint s = 0u; s < seg; ++s) {
    offset += hemo_spawn_served(s, n, ends);
  }
  return offset;
}

void main() {
  const uint i = hemo_global_index();
  const uint n = pc.n;
  const uint ends = inflow.endCount;
  const uint parkedSeg = 2u * ends;
  if (pc.mode == HEMO_SPAWN_FLAGS) {
    if (i == 0u) {
      scan[(parkedSeg + 1u) * n] = 0u;
      // Each buffer's deficit, the particles it holds fewer than it started with: what left it
      // into the lumen or past its end, less what came into it from the lumen and its images
      // (integers; the differences are taken modulo 2^32, exact while below 2^31).
      for (uint e = 0u; e < ends; ++e) {
        const int deficit = int(counters[HEMO_OPEN_COUNTER_LEAVE(e)] + counters[HEMO_OPEN_COUNTER_PARKED(e)] -
                                counters[HEMO_OPEN_COUNTER_ENTER(e)] - counters[HEMO_OPEN_COUNTER_SPAWNED(e)]);
        scan[(parkedSeg + 1u) * n + 1u + e] = uint(max(deficit, 0));
      }
    }
    if (i < n) {
      const uint c = pending[i];  // (a pending slot is never a free one)
      const uint mine = c != 0u ? hemo_spawn_segment(c, ends)
                                : (uint(velocities[i].w) == HEMO_KIND_PARKED ? parkedSeg : parkedSeg + 1u);
      for (uint seg = 0u; seg <= parkedSeg; ++seg) {
        scan[seg * n + i] = seg == mine ? 1u : 0u;
      }
    }
    return;
  }
  if (i >= n) {
    return;
  }
  const uint c = pending[i];
  if (c != 0u) {
    const uint seg = hemo_spawn_segment(c, ends);
    const uint e = seg < ends ? seg : seg - ends;
    const uint rank = scan[seg * n + i] - scan[seg * n];
    const bool served = rank < hemo_spawn_served(seg, n, ends);
    const uint k = hemo_spawn_offset(seg, n, ends) + rank;  // its place in the served order
    if (pc.mode == HEMO_SPAWN_SCATTER) {
      if (served) {
        crossers[k] = i | (e << HEMO_SPAWN_END_SHIFT);
      }
      return;
    }
    // HEMO_SPAWN_COPY (only this invocation touches its flag; the copies below read the
    // crosser's own data). A crosser not served is not needed: its buffer is full.
    if (!served || k < scan[(parkedSeg + 1u) * n] - scan[parkedSeg * n]) {
      pending[i] = 0u;
    } else {
      atomicAdd(status[HEMO_STATUS_OPEN_SHORTFALL], 1u);
    }
    return;
  }
  if (pc.mode != HEMO_SPAWN_COPY || uint(velocities[i].w) != HEMO_KIND_PARKED) {
    return;
  }
  const uint k = scan[parkedSeg * n + i] - scan[parkedSeg * n];  // this slot's rank among the parked ones
  if (k >= hemo_spawn_offset(parkedSeg, n, ends)) {
    return;
  }
  const uint e = crossers[k] >> HEMO_SPAWN_END_SHIFT;
  const uint from = crossers[k] & ((1u << HEMO_SPAWN_END_SHIFT) - 1u);
  const vec4 x = positions[from];
  // (a buffer length back along the end's axis: the inlet's upstream; an outlet's, of reverse
  // flow, downstream)
  positions[i] = vec4(x.xyz - inflow.ends[e].shift.xyz, x.w);
  velocities[i] = velocities[from];
  normals[i] = vec4(normals[from].xyz, 0.0);  // (the image holds no credit)
  atomicAdd(counters[HEMO_OPEN_COUNTER_SPAWNED(e)], 1u);
}
