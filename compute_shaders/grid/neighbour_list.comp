#version 450
// Neighbour list from the sorted particles and the cell table: every particle j != i with
// |x_i - x_j| < radius (minimum image on periodic axes), in the order the scan visits the
// cells (ascending slots unless a periodic axis wraps). radius must not exceed the cell size.
#extension GL_GOOGLE_include_directive : require
#include "interface/grid.h"
#include "common/index.glsl"
#include "common/grid.glsl"

layout(std430, binding = HEMO_NLIST_BINDING_POSITIONS) readonly buffer Positions { vec4 positions[]; };
layout(std430, binding = HEMO_NLIST_BINDING_CELL_START) readonly buffer CellStart { uint cellStart[]; };
layout(std430, binding = HEMO_NLIST_BINDING_COUNTS) writeonly buffer Counts { uint neighbourCount[]; };
layout(std430, binding = HEMO_NLIST_BINDING_LIST) writeonly buffer List { uint neighbourList[]; };
layout(push_constant) uniform Push {
  HemoGrid grid;
  float radius;
  uint capacity;
} pc;

void main() {
  const uint i = hemo_global_index();
  if (i >= pc.grid.dimsN.w) {
    return;
  }
  const vec3 p = positions[i].xyz;
  bool outside;
  const ivec3 c = hemo_cell_coords(p, pc.grid, outside);
  ivec2 xr[2];
  const int ranges = hemo_x_ranges(c.x, pc.grid, xr[0], xr[1]);
  const float r2 = pc.radius * pc.radius;
  uint count = 0u;
  const uint listBase = i * pc.capacity;
  for (int dz = -1; dz <= 1; ++dz) {
    const int z = hemo_grid_step(c.z, dz, pc.grid.dimsN.z, pc.grid.periodic.z);
    for (int dy = -1; dy <= 1 && z >= 0; ++dy) {
      const int y = hemo_grid_step(c.y, dy, pc.grid.dimsN.y, pc.grid.periodic.y);
      for (int s = 0; s < ranges && y >= 0; ++s) {
        const uint jEnd = cellStart[hemo_cell_linear(ivec3(xr[s].y, y, z), pc.grid.dimsN.xyz) + 1u];
        for (uint j = cellStart[hemo_cell_linear(ivec3(xr[s].x, y, z), pc.grid.dimsN.xyz)]; j < jEnd; ++j) {
          const vec3 d = hemo_grid_min_image(p - positions[j].xyz, pc.grid);
          if (j != i && dot(d, d) < r2) {
            if (count < pc.capacity) {
              neighbourList[listBase + count] = j;
            }
            ++count;
          }
        }
      }
    }
  }
  neighbourCount[i] = count;
}
