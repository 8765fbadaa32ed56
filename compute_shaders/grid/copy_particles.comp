#version 450
// Copies the live particle arrays into the scratch arrays, which the reorder then gathers
// from in cell order back into the live arrays (so the live buffers never change identity).
#extension GL_GOOGLE_include_directive : require
#include "interface/grid.h"
#include "common/index.glsl"

layout(std430, binding = HEMO_COPY_BINDING_POS_IN) readonly buffer PosIn { vec4 posIn[]; };
layout(std430, binding = HEMO_COPY_BINDING_VEL_IN) readonly buffer VelIn { vec4 velIn[]; };
layout(std430, binding = HEMO_COPY_BINDING_NORMAL_IN) readonly buffer NormalIn { vec4 normalIn[]; };
layout(std430, binding = HEMO_COPY_BINDING_ID_IN) readonly buffer IdIn { uint idIn[]; };
layout(std430, binding = HEMO_COPY_BINDING_POS_OUT) writeonly buffer PosOut { vec4 posOut[]; };
layout(std430, binding = HEMO_COPY_BINDING_VEL_OUT) writeonly buffer VelOut { vec4 velOut[]; };
layout(std430, binding = HEMO_COPY_BINDING_NORMAL_OUT) writeonly buffer NormalOut { vec4 normalOut[]; };
layout(std430, binding = HEMO_COPY_BINDING_ID_OUT) writeonly buffer IdOut { uint idOut[]; };
layout(push_constant) uniform Push { uint n; } pc;

void main() {
  const uint i = hemo_global_index();
  if (i >= pc.n) {
    return;
  }
  posOut[i] = posIn[i];
  velOut[i] = velIn[i];
  normalOut[i] = normalIn[i];
  idOut[i] = idIn[i];
}
