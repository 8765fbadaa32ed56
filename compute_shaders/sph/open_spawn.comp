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

// The flag segment of pending value c (1-4) and the parked slots' (c = 0 gives segment 4).
uint hemo_spawn_segment(uint c) {
  return c == 0u ? 4u : c - 1u;
}

// How many crossers of segment `seg` (0-3: pending 1-4) are served, from the scan: each end
// serves its owing crossers first, then those that spent a credit, up to its deficit.
uint hemo_spawn_served(uint seg, uint n) {
  const uint e = seg & 1u;
  const uint deficit = scan[5u * n + 1u + e];
  const uint owing = scan[(e + 1u) * n] - scan[e * n];
  const uint owingServed = min(deficit, owing);
  if (seg < 2u) {
    return owingServed;
  }
  return min(deficit - owingServed, scan[(seg + 1u) * n] - scan[seg * n]);
}

// Where segment `seg`'s served crossers start in the served order (owing inlet, owing outlet,
// credited inlet, credited outlet).
uint hemo_spawn_offset(uint seg, uint n) {
  uint offset = 0u;
  for (uint s = 0u; s < seg; ++s) {
    offset += hemo_spawn_served(s, n);
  }
  return offset;
}

void main() {
  const uint i = hemo_global_index();
  const uint n = pc.n;
  if (pc.mode == HEMO_SPAWN_FLAGS) {
    if (i == 0u) {
      scan[5u * n] = 0u;
      // Each buffer's deficit, the particles it holds fewer than it started with: what left it
      // into the lumen or past its end, less what came into it from the lumen and its images
      // (integers; the differences are taken modulo 2^32, exact while below 2^31).
      const int inlet = int(counters[HEMO_OPEN_COUNTER_IN] + counters[HEMO_OPEN_COUNTER_PARKED_START] -
                            counters[HEMO_OPEN_COUNTER_IN_BACK] - counters[HEMO_OPEN_COUNTER_SPAWNED]);
      const int outlet = int(counters[HEMO_OPEN_COUNTER_OUT_BACK] + counters[HEMO_OPEN_COUNTER_PARKED_END] -
                             counters[HEMO_OPEN_COUNTER_OUT] - counters[HEMO_OPEN_COUNTER_SPAWNED_OUTLET]);
      scan[5u * n + 1u] = uint(max(inlet, 0));
      scan[5u * n + 2u] = uint(max(outlet, 0));
    }
    if (i < n) {
      const uint c = pending[i];  // (a pending slot is never a free one)
      for (uint seg = 0u; seg < 4u; ++seg) {
        scan[seg * n + i] = c == seg + 1u ? 1u : 0u;
      }
      scan[4u * n + i] = c == 0u && uint(velocities[i].w) == HEMO_KIND_PARKED ? 1u : 0u;
    }
    return;
  }
  if (i >= n) {
    return;
  }
  const uint c = pending[i];
  if (c != 0u) {
    const uint seg = hemo_spawn_segment(c);
    const uint rank = scan[seg * n + i] - scan[seg * n];
    const bool served = rank < hemo_spawn_served(seg, n);
    const uint k = hemo_spawn_offset(seg, n) + rank;  // its place in the served order
    if (pc.mode == HEMO_SPAWN_SCATTER) {
      if (served) {
        crossers[k] = i | ((seg & 1u) != 0u ? 0x80000000u : 0u);  // (bit 31: the outlet's)
      }
      return;
    }
    // HEMO_SPAWN_COPY (only this invocation touches its flag; the copies below read the
    // crosser's own data). A crosser not served is not needed: its buffer is full.
    if (!served || k < scan[5u * n] - scan[4u * n]) {
      pending[i] = 0u;
    } else {
      atomicAdd(status[HEMO_STATUS_OPEN_SHORTFALL], 1u);
    }
    return;
  }
  if (pc.mode != HEMO_SPAWN_COPY || uint(velocities[i].w) != HEMO_KIND_PARKED) {
    return;
  }
  const uint k = scan[4u * n + i] - scan[4u * n];  // this slot's rank among the parked ones
  if (k >= hemo_spawn_offset(4u, n)) {
    return;
  }
  const bool outletImage = (crossers[k] & 0x80000000u) != 0u;
  const uint from = crossers[k] & 0x7fffffffu;
  const vec4 x = positions[from];
  // (a buffer length back along the end's axis: the inlet's upstream; the outlet's, of reverse
  // flow, downstream)
  const vec3 shift = inflow.ends[outletImage ? 1 : 0].shift.xyz;
  positions[i] = vec4(x.xyz - shift, x.w);
  velocities[i] = velocities[from];
  normals[i] = vec4(normals[from].xyz, 0.0);  // (the image holds no credit)
  atomicAdd(counters[outletImage ? HEMO_OPEN_COUNTER_SPAWNED_OUTLET : HEMO_OPEN_COUNTER_SPAWNED], 1u);
}
