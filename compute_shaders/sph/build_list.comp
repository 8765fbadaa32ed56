#version 450
// The per-particle neighbour list (a Verlet list): every other particle closer than the list
// radius = support * (1 + skin), as slots of the sorted order (ascending unless a periodic x
// axis wraps; the order only has to be the same every build). The skin lets the
// list serve the following steps until some particle has moved half of it (the solver's
// gate decides on the GPU when to rebuild). Fluid particles list all neighbours; boundary
// particles list only their fluid neighbours (all boundary_pressure.comp needs), and those
// with no fluid in their 27 cells skip the scan.
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "common/index.glsl"
#include "common/grid.glsl"
#include "common/sph_params.glsl"

layout(std430, binding = HEMO_BUILD_BINDING_POSITIONS) readonly buffer Positions { vec4 positions[]; };
layout(std430, binding = HEMO_BUILD_BINDING_VELOCITIES) readonly buffer Velocities { vec4 velocities[]; };
layout(std430, binding = HEMO_BUILD_BINDING_CELL_START) readonly buffer CellStart { uint cellStart[]; };
layout(std430, binding = HEMO_BUILD_BINDING_PARAMS) readonly buffer Params { SphParams params; };
layout(std430, binding = HEMO_BUILD_BINDING_NCOUNT) writeonly buffer Counts { uint neighbourCount[]; };
layout(std430, binding = HEMO_BUILD_BINDING_NLIST) writeonly buffer List { uint neighbourList[]; };
layout(std430, binding = HEMO_BUILD_BINDING_STATUS) buffer Status { uint status[]; };
layout(std430, binding = HEMO_BUILD_BINDING_FLUID_CELLS) readonly buffer FluidCells { uint fluidCells[]; };
layout(push_constant) uniform Push { HemoGrid grid; } pc;

void main() {
  const uint i = hemo_global_index();
  if (i >= pc.grid.dimsN.w) {
    return;
  }
  const bool fluidI = uint(velocities[i].w) == HEMO_KIND_FLUID;
  const vec3 xi = positions[i].xyz;
  const float list2 = params.listRadius * params.listRadius;
  const uint capacity = params.neighbourCapacity;
  const HemoPairParams pp = hemo_pair_params();
  const uvec3 dims = pc.grid.dimsN.xyz;

  bool outside;
  const ivec3 c = hemo_cell_coords(xi, pc.grid, outside);
  ivec2 xr[2];
  const int ranges = hemo_x_ranges(c.x, pc.grid, xr[0], xr[1]);
  // The nine rows (dz, dy) around the cell: bit (dz + 1) * 3 + (dy + 1) set when the row is
  // on the grid and worth scanning. A boundary particle needs only its fluid neighbours, so
  // it scans only rows that hold fluid, and none at all when no row does.
  uint rows = 0u;
  for (int dz = -1; dz <= 1; ++dz) {
    const int z = hemo_grid_step(c.z, dz, dims.z, pc.grid.periodic.z);
    for (int dy = -1; dy <= 1 && z >= 0; ++dy) {
      const int y = hemo_grid_step(c.y, dy, dims.y, pc.grid.periodic.y);
      if (y < 0) {
        continue;
      }
      bool wanted = fluidI;
      for (int s = 0; s < ranges && !wanted; ++s) {
        for (int x = xr[s].x; x <= xr[s].y; ++x) {
          wanted = wanted || fluidCells[hemo_cell_linear(ivec3(x, y, z), dims)] != 0u;
        }
      }
      if (wanted) {
        rows |= 1u << uint((dz + 1) * 3 + (dy + 1));
      }
    }
  }
  uint count = 0u;
  for (int dz = -1; dz <= 1; ++dz) {
    const int z = hemo_grid_step(c.z, dz, dims.z, pc.grid.periodic.z);
    for (int dy = -1; dy <= 1; ++dy) {
      if ((rows & (1u << uint((dz + 1) * 3 + (dy + 1)))) == 0u) {
        continue;
      }
      const int y = hemo_grid_step(c.y, dy, dims.y, pc.grid.periodic.y);
      for (int s = 0; s < ranges; ++s) {
        const uint jEnd = cellStart[hemo_cell_linear(ivec3(xr[s].y, y, z), dims) + 1u];
        for (uint j = cellStart[hemo_cell_linear(ivec3(xr[s].x, y, z), dims)]; j < jEnd; ++j) {
          const vec3 d = hemo_grid_min_image(xi - positions[j].xyz, pc.grid);
          if (j != i && dot(d, d) < list2 && (fluidI || uint(velocities[j].w) == HEMO_KIND_FLUID)) {
            if (count < capacity) {
              neighbourList[hemo_list_slot(i, count, pp)] = j;
            }
            ++count;
          }
        }
      }
    }
  }
  neighbourCount[i] = min(count, capacity);
  if (count > capacity) {
    atomicAdd(status[HEMO_STATUS_NEIGHBOUR_OVERFLOW], 1u);
  }
  atomicMax(status[HEMO_STATUS_MAX_NEIGHBOURS], count);
}
