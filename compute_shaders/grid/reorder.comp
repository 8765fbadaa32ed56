#version 450
// Neighbour grid, step 4 (after the sort and the cell ranges): gathers particle data
// (positions, velocities, normals, ids) from the scratch copy into cell order in the live
// arrays, keeps the positions of this build (for the list's validity check; w: the particle's
// kind, so the list build finds position and kind in one load) and records where each
// particle id now lives.
#extension GL_GOOGLE_include_directive : require
#include "interface/grid.h"
#include "common/index.glsl"

layout(binding = HEMO_REORDER_BINDING_PAIRS) uniform usamplerBuffer pairs;  // (cell, source slot)
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
  const int src = int(texelFetch(pairs, int(i)).y);
  const vec4 p = texelFetch(posIn, src);
  const vec4 v = texelFetch(velIn, src);
  posOut[i] = p;
  posAtBuild[i] = vec4(p.xyz, v.w);
  velOut[i] = v;
  normalOut[i] = texelFetch(normalIn, src);
  const uint id = texelFetch(idIn, src).x;
  idOut[i] = id;
  if (id < pc.idCapacity) {
    slotOfId[id] = i;  // ids are unique, so this scatter has exactly one writer per entry
  }
}
