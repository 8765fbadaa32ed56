#version 450
// Summation density over fluid and boundary neighbours (boundary particles act as virtual
// fluid particles so the density does not drop at walls), Tait pressure (Monaghan 1994;
// Batchelor's gamma = 7) and the per-particle neighbour list (radius = support * (1 + skin),
// so the force pass and later stages of a step can reuse it).
//   rho_i = sum_j m_j W(|x_i - x_j|, h)   (j includes i)
//   p_i   = B ((rho_i / rho0)^7 - 1),  B = c0^2 rho0 / 7,  optionally clamped at 0
// Boundary particles get a list of their fluid neighbours only (for boundary_pressure.comp,
// which then sets their state).
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "common/index.glsl"
#include "common/grid.glsl"
#include "common/kernel.glsl"
#include "common/sph_params.glsl"
#include "common/tait.glsl"

layout(std430, binding = HEMO_DENSITY_BINDING_POSITIONS) readonly buffer Positions { vec4 positions[]; };
layout(std430, binding = HEMO_DENSITY_BINDING_VELOCITIES) readonly buffer Velocities { vec4 velocities[]; };
layout(std430, binding = HEMO_DENSITY_BINDING_CELL_START) readonly buffer CellStart { uint cellStart[]; };
layout(std430, binding = HEMO_DENSITY_BINDING_PARAMS) readonly buffer Params { SphParams params; };
layout(std430, binding = HEMO_DENSITY_BINDING_STATE) writeonly buffer State { vec4 state[]; };
layout(std430, binding = HEMO_DENSITY_BINDING_NCOUNT) writeonly buffer Counts { uint neighbourCount[]; };
layout(std430, binding = HEMO_DENSITY_BINDING_NLIST) writeonly buffer List { uint neighbourList[]; };
layout(std430, binding = HEMO_DENSITY_BINDING_STATUS) buffer Status { uint status[]; };
layout(std430, binding = HEMO_DENSITY_BINDING_FLUID_CELLS) readonly buffer FluidCells { uint fluidCells[]; };
layout(push_constant) uniform Push { vec4 originInvCell; uvec4 dimsN; } pc;

void main() {
  const uint i = hemo_global_index();
  if (i >= pc.dimsN.w) {
    return;
  }
  const bool fluidI = uint(velocities[i].w) == HEMO_KIND_FLUID;
  const vec4 pi = positions[i];
  const float h = params.h;
  const float support2 = params.supportRadius * params.supportRadius;
  const float list2 = params.listRadius * params.listRadius;
  const uint capacity = params.neighbourCapacity;
  const uint listBase = i * capacity;

  float rho = pi.w * hemo_kernel_w(0.0, h, params.kernelNorm);
  uint count = 0u;
  bool outside;
  const ivec3 c = hemo_cell_coords(pi.xyz, pc.originInvCell, pc.dimsN.xyz, outside);
  const ivec3 hi = ivec3(pc.dimsN.xyz) - 1;
  const int x0 = max(c.x - 1, 0);
  const int x1 = min(c.x + 1, hi.x);
  uint fluidRows = 0x1ffu;  // fluid particles scan all nine rows
  if (!fluidI) {
    // A boundary particle needs only its fluid neighbours: none in its 27 cells, no work.
    fluidRows = 0u;
    // One bit per row (dz, dy) of the 3 x 3 rows that holds fluid; the others are skipped.
    for (int z = max(c.z - 1, 0); z <= min(c.z + 1, hi.z); ++z) {
      for (int y = max(c.y - 1, 0); y <= min(c.y + 1, hi.y); ++y) {
        const uint rowFirst = hemo_cell_linear(ivec3(x0, y, z), pc.dimsN.xyz);
        bool rowHasFluid = false;
        for (uint k = 0u; k <= uint(x1 - x0); ++k) {
          rowHasFluid = rowHasFluid || fluidCells[rowFirst + k] != 0u;
        }
        if (rowHasFluid) {
          fluidRows |= 1u << uint((z - c.z + 1) * 3 + (y - c.y + 1));
        }
      }
    }
    if (fluidRows == 0u) {
      neighbourCount[i] = 0u;
      state[i] = vec4(params.rho0, 0.0, 0.0, 0.0);
      return;
    }
  }
  for (int z = max(c.z - 1, 0); z <= min(c.z + 1, hi.z); ++z) {
    for (int y = max(c.y - 1, 0); y <= min(c.y + 1, hi.y); ++y) {
      if ((fluidRows & (1u << uint((z - c.z + 1) * 3 + (y - c.y + 1)))) == 0u) {
        continue;
      }
      const uint rowFirst = hemo_cell_linear(ivec3(x0, y, z), pc.dimsN.xyz);
      const uint jEnd = cellStart[rowFirst + uint(x1 - x0) + 1u];
      for (uint j = cellStart[rowFirst]; j < jEnd; ++j) {
        const vec4 pj = positions[j];
        const vec3 d = pi.xyz - pj.xyz;
        const float r2 = dot(d, d);
        if (j != i && r2 < list2 && (fluidI || uint(velocities[j].w) == HEMO_KIND_FLUID)) {
          if (count < capacity) {
            neighbourList[listBase + count] = j;
          }
          ++count;
          if (r2 < support2) {
            rho += pj.w * hemo_kernel_w(sqrt(r2), h, params.kernelNorm);
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
  if (!fluidI) {
    state[i] = vec4(params.rho0, 0.0, 0.0, 0.0);  // replaced by boundary_pressure.comp
    return;
  }

  state[i] = vec4(rho, hemo_tait_pressure(rho, params), 0.0, 0.0);
}
