#version 450
// The open ends' refill (interface/sph.h, HEMO_SPAWN_*; hemo/sim/inflow.hpp): at the start
// of every step that rebuilds the neighbour list, each fluid particle that left a buffer into
// the lumen since the last refill gets its image one buffer length back along the end's axis,
// at the buffer's far end, in a parked slot, so the buffer holds the same particles as it did
// (the image of a periodic seam, made without one). Three modes over the fluid's slots, with the scan of the
// flags between FLAGS and SCATTER (gpu::PrefixScan): the k-th crosser in slot order takes the
// k-th parked slot in slot order, so the outcome does not depend on the order the invocations
// run in. Run before the grid's build, which sorts the new particles into the list.
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

void main() {
  const uint i = hemo_global_index();
  const uint n = pc.n;
  if (pc.mode == HEMO_SPAWN_FLAGS) {
    if (i == 0u) {
      scan[2u * n] = 0u;
    }
    if (i < n) {
      const bool crosser = pending[i] != 0u;  // (a pending slot is never a free one)
      scan[i] = crosser ? 1u : 0u;
      scan[n + i] = !crosser && uint(velocities[i].w) == HEMO_KIND_PARKED ? 1u : 0u;
    }
    return;
  }
  if (i >= n) {
    return;
  }
  if (pc.mode == HEMO_SPAWN_SCATTER) {
    if (pending[i] != 0u) {
      crossers[scan[i]] = i | (pending[i] == 2u ? 0x80000000u : 0u);  // (bit 31: the outlet's)
    }
    return;
  }
  // HEMO_SPAWN_COPY. scan[n] is the number of crossers, scan[2n] - scan[n] of parked slots.
  const uint crossings = scan[n];
  const uint parked = scan[2u * n] - crossings;
  if (pending[i] != 0u) {
    // (only this invocation touches its flag; the copies below read the crosser's own data)
    if (scan[i] < parked) {
      pending[i] = 0u;
    } else {
      atomicAdd(status[HEMO_STATUS_OPEN_SHORTFALL], 1u);
    }
    return;
  }
  if (uint(velocities[i].w) != HEMO_KIND_PARKED) {
    return;
  }
  const uint k = scan[n + i] - crossings;  // this slot's rank among the parked ones
  if (k >= crossings) {
    return;
  }
  const uint c = crossers[k] & 0x7fffffffu;
  const vec4 x = positions[c];
  // (a buffer length back along the end's axis: the inlet's upstream; the outlet's, of reverse
  // flow, downstream)
  const vec3 shift = inflow.ends[(crossers[k] & 0x80000000u) != 0u ? 1 : 0].shift.xyz;
  positions[i] = vec4(x.xyz - shift, x.w);
  velocities[i] = velocities[c];
  normals[i] = normals[c];
  atomicAdd(counters[HEMO_OPEN_COUNTER_SPAWNED], 1u);
}
