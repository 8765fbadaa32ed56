#version 450
// Flags every grid cell that holds at least one fluid particle (one invocation per cell,
// gathering over the cell's slots), so boundary particles with no fluid in their 27 cells
// skip the list build.
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "common/index.glsl"

layout(std430, binding = HEMO_MARK_BINDING_CELL_START) readonly buffer CellStart { uint cellStart[]; };
layout(std430, binding = HEMO_MARK_BINDING_VELOCITIES) readonly buffer Velocities { vec4 velocities[]; };
layout(std430, binding = HEMO_MARK_BINDING_FLAGS) writeonly buffer Flags { uint fluidCells[]; };
layout(push_constant) uniform Push { uint cellCount; } pc;

void main() {
  const uint c = hemo_global_index();
  if (c >= pc.cellCount) {
    return;
  }
  uint flag = 0u;
  const uint end = cellStart[c + 1u];
  for (uint j = cellStart[c]; j < end && flag == 0u; ++j) {
    flag = uint(velocities[j].w) == HEMO_KIND_FLUID ? 1u : 0u;
  }
  fluidCells[c] = flag;
}
