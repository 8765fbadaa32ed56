#version 450
// Flags every grid cell that holds at least one fluid particle (one invocation per cell,
// gathering over the cell's slots), so boundary particles with no fluid in their 27 cells
// skip the list build.
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "common/index.glsl"

// Read-only inputs are uniform texel buffers (interface/sph.h, "texel slots").
layout(binding = HEMO_MARK_BINDING_CELL_START) uniform usamplerBuffer cellStart;
layout(binding = HEMO_MARK_BINDING_VELOCITIES) uniform samplerBuffer velocities;
layout(std430, binding = HEMO_MARK_BINDING_FLAGS) writeonly buffer Flags { uint fluidCells[]; };
layout(push_constant) uniform Push { uint cellCount; } pc;

void main() {
  const uint c = hemo_global_index();
  if (c >= pc.cellCount) {
    return;
  }
  uint flag = 0u;
  const uint end = texelFetch(cellStart, int(c + 1u)).x;
  for (uint j = texelFetch(cellStart, int(c)).x; j < end && flag == 0u; ++j) {
    flag = uint(texelFetch(velocities, int(j)).w) == HEMO_KIND_FLUID ? 1u : 0u;
  }
  fluidCells[c] = flag;
}
