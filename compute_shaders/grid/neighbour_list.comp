#version 450
// Neighbour list from the sorted particles and the cell table: every particle j != i with
// |x_i - x_j| < radius, as ascending slots (the scan visits cells in increasing linear order,
// and slots within the three x-adjacent cells of a row are one contiguous range).
// radius must not exceed the cell size.
#extension GL_GOOGLE_include_directive : require
#include "interface/grid.h"
#include "common/index.glsl"
#include "common/grid.glsl"

layout(std430, binding = HEMO_NLIST_BINDING_POSITIONS) readonly buffer Positions { vec4 positions[]; };
layout(std430, binding = HEMO_NLIST_BINDING_CELL_START) readonly buffer CellStart { uint cellStart[]; };
layout(std430, binding = HEMO_NLIST_BINDING_COUNTS) writeonly buffer Counts { uint neighbourCount[]; };
layout(std430, binding = HEMO_NLIST_BINDING_LIST) writeonly buffer List { uint neighbourList[]; };
layout(push_constant) uniform Push {
  vec4 originInvCell;
  uvec4 dimsN;
  float radius;
  uint capacity;
} pc;

void main() {
  const uint i = hemo_global_index();
  if (i >= pc.dimsN.w) {
    return;
  }
  const vec3 p = positions[i].xyz;
  bool outside;
  const ivec3 c = hemo_cell_coords(p, pc.originInvCell, pc.dimsN.xyz, outside);
  const ivec3 hi = ivec3(pc.dimsN.xyz) - 1;
  const int x0 = max(c.x - 1, 0);
  const int x1 = min(c.x + 1, hi.x);
  const float r2 = pc.radius * pc.radius;
  uint count = 0u;
  const uint listBase = i * pc.capacity;
  for (int z = max(c.z - 1, 0); z <= min(c.z + 1, hi.z); ++z) {
    for (int y = max(c.y - 1, 0); y <= min(c.y + 1, hi.y); ++y) {
      const uint rowFirst = hemo_cell_linear(ivec3(x0, y, z), pc.dimsN.xyz);
      const uint rowLast = rowFirst + uint(x1 - x0);
      const uint jEnd = cellStart[rowLast + 1u];
      for (uint j = cellStart[rowFirst]; j < jEnd; ++j) {
        const vec3 d = p - positions[j].xyz;
        if (j != i && dot(d, d) < r2) {
          if (count < pc.capacity) {
            neighbourList[listBase + count] = j;
          }
          ++count;
        }
      }
    }
  }
  neighbourCount[i] = count;
}
