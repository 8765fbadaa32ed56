#version 450
// Neighbour grid, step 1 of the counting sort (interface/grid.h): the key of every particle,
// its cell, or in a grid of two parts cell + cellCount for a particle that is not fluid (nor a
// parked fluid slot), so
// the fluid sorts first; and its rank among the particles of that key, from an atomic count
// per key (the order of those ranks depends on scheduling; grid/reorder.comp removes it).
// Particles outside the grid are clamped into the border cells and counted (on periodic
// axes they wrap instead); a particle with a non-finite coordinate goes to cell 0 and is
// counted separately so the caller can stop. The particle's data is copied to the scratch
// arrays, which grid/reorder.comp gathers back in cell order.
#extension GL_GOOGLE_include_directive : require
#include "interface/grid.h"
#include "common/index.glsl"
#include "common/grid.glsl"

layout(binding = HEMO_HASH_BINDING_POSITIONS) uniform samplerBuffer positions;  // a texel slot
layout(binding = HEMO_HASH_BINDING_VELOCITIES) uniform samplerBuffer velocities;  // w: kind (a texel slot)
layout(std430, binding = HEMO_HASH_BINDING_PAIRS) writeonly buffer Pairs { uvec2 pairs[]; };
layout(std430, binding = HEMO_HASH_BINDING_COUNTERS) buffer Counters { uint counters[]; };
layout(std430, binding = HEMO_HASH_BINDING_KEY_COUNTS) buffer KeyCounts { uint keyCounts[]; };
layout(binding = HEMO_HASH_BINDING_NORMALS) uniform samplerBuffer normals;
layout(binding = HEMO_HASH_BINDING_IDS) uniform usamplerBuffer ids;
layout(std430, binding = HEMO_HASH_BINDING_POS_OUT) writeonly buffer PosOut { vec4 posOut[]; };
layout(std430, binding = HEMO_HASH_BINDING_VEL_OUT) writeonly buffer VelOut { vec4 velOut[]; };
layout(std430, binding = HEMO_HASH_BINDING_NORMAL_OUT) writeonly buffer NormalOut { vec4 normalOut[]; };
layout(std430, binding = HEMO_HASH_BINDING_ID_OUT) writeonly buffer IdOut { uint idOut[]; };
layout(push_constant) uniform Push { HemoGrid grid; } pc;

void main() {
  const uint i = hemo_global_index();
  if (i >= pc.grid.dimsN.w) {
    return;
  }
  const vec4 p4 = texelFetch(positions, int(i));
  const vec4 v4 = texelFetch(velocities, int(i));
  posOut[i] = p4;
  velOut[i] = v4;
  normalOut[i] = texelFetch(normals, int(i));
  idOut[i] = texelFetch(ids, int(i)).x;
  const vec3 p = p4.xyz;
  uint cell = 0u;
  if (any(isnan(p)) || any(isinf(p))) {
    atomicAdd(counters[HEMO_COUNTER_NONFINITE], 1u);
  } else {
    bool outside;
    const ivec3 c = hemo_cell_coords(p, pc.grid, outside);
    cell = hemo_cell_linear(c, pc.grid.dimsN.xyz);
    // (a parked slot lies outside on purpose: interface/sph.h, HEMO_KIND_PARKED)
    if (outside && uint(v4.w) != HEMO_GRID_PARKED_KIND) {
      atomicAdd(counters[HEMO_COUNTER_OUTSIDE], 1u);
    }
  }
  if (pc.grid.periodic.w == 2u && uint(v4.w) != HEMO_GRID_FLUID_KIND && uint(v4.w) != HEMO_GRID_PARKED_KIND) {
    const uvec3 dims = pc.grid.dimsN.xyz;
    cell += dims.x * dims.y * dims.z;
  }
  pairs[i] = uvec2(cell, atomicAdd(keyCounts[cell], 1u));
}
