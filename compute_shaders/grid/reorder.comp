#version 450
// Neighbour grid, step 4 of the counting sort (interface/grid.h): every particle's final slot
// is its key's start plus the number of particles of the same key with a smaller source slot
// (a stable sort, whatever order the ranks came in; a cell holds a few particles, so the count
// is short). Moves the particle data (positions, velocities, normals, ids) from the scratch
// copy to that slot of the live arrays, keeps the positions of this build (for the list's
// validity check; w: the particle's kind, so the list build finds position and kind in one
// load) and records where each particle id now lives. The final slots are a permutation:
// every output has exactly one writer.
#extension GL_GOOGLE_include_directive : require
#include "interface/grid.h"
#include "common/index.glsl"

layout(binding = HEMO_REORDER_BINDING_ORDER) uniform usamplerBuffer order;  // (key, source slot)
layout(binding = HEMO_REORDER_BINDING_CELL_START) uniform usamplerBuffer cellStart;
layout(binding = HEMO_REORDER_BINDING_POS_IN) uniform samplerBuffer posIn;
layout(binding = HEMO_REORDER_BINDING_VEL_IN) uniform samplerBuffer velIn;
layout(binding = HEMO_REORDER_BINDING_ID_IN) uniform usamplerBuffer idIn;
layout(std430, binding = HEMO_REORDER_BINDING_POS_OUT) writeonly buffer PosOut { vec4 posOut[]; };
layout(std430, binding = HEMO_REORDER_BINDING_VEL_OUT) writeonly buffer VelOut { vec4 velOut[]; };
layout(std430, binding = HEMO_REORDER_BINDING_ID_OUT) writeonly buffer IdOut { uint idOut[]; };
layout(std430, binding = HEMO_REORDER_BINDING_SLOT_OF_ID) writeonly buffer SlotOfId { uint slotOfId[]; };
layout(binding = HEMO_REORDER_BINDING_NORMAL_IN) uniform samplerBuffer normalIn;
layout(std430, binding = HEMO_REORDER_BINDING_NORMAL_OUT) writeonly buffer NormalOut { vec4 normalOut[]; };
layout(std430, binding = HEMO_REORDER_BINDING_POS_AT_BUILD) writeonly buffer PosAtBuild { vec4 posAtBuild[]; };
layout(push_constant) uniform Push { uint n; uint idCapacity; } pc;

void main() {
  const uint i = hemo_global_index();
  if (i >= pc.n) {
    return;
  }
  const uvec2 ks = texelFetch(order, int(i)).xy;
  const uint first = texelFetch(cellStart, int(ks.x)).x;
  const uint end = texelFetch(cellStart, int(ks.x) + 1).x;
  uint slot = first;
  for (uint m = first; m < end; ++m) {
    slot += texelFetch(order, int(m)).y < ks.y ? 1u : 0u;
  }
  const int src = int(ks.y);
  const vec4 p = texelFetch(posIn, src);
  const vec4 v = texelFetch(velIn, src);
  posOut[slot] = p;
  posAtBuild[slot] = vec4(p.xyz, v.w);
  velOut[slot] = v;
  normalOut[slot] = texelFetch(normalIn, src);
  const uint id = texelFetch(idIn, src).x;
  idOut[slot] = id;
  if (id < pc.idCapacity) {
    slotOfId[id] = slot;  // ids are unique, so this scatter has exactly one writer per entry
  }
}
