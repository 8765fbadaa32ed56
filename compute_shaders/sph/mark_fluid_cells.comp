#version 450
// Marks the grid cells that hold fluid particles (integer atomicOr of 1: the result does not
// depend on order). The density pass lets a boundary particle skip its neighbour search when
// none of its 27 cells is marked: most of a tank's wall never touches the fluid.
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "common/index.glsl"
#include "common/grid.glsl"

layout(std430, binding = HEMO_MARK_BINDING_POSITIONS) readonly buffer Positions { vec4 positions[]; };
layout(std430, binding = HEMO_MARK_BINDING_VELOCITIES) readonly buffer Velocities { vec4 velocities[]; };
layout(std430, binding = HEMO_MARK_BINDING_FLAGS) buffer Flags { uint fluidCells[]; };
layout(push_constant) uniform Push { vec4 originInvCell; uvec4 dimsN; } pc;

void main() {
  const uint i = hemo_global_index();
  if (i >= pc.dimsN.w || uint(velocities[i].w) != HEMO_KIND_FLUID) {
    return;
  }
  bool outside;
  const ivec3 c = hemo_cell_coords(positions[i].xyz, pc.originInvCell, pc.dimsN.xyz, outside);
  atomicOr(fluidCells[hemo_cell_linear(c, pc.dimsN.xyz)], 1u);
}
