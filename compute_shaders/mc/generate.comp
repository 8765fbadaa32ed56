#version 450
// Generate: one invocation per active run writes the triangles of its voxels at the run's
// scanned offset, in voxel order and in the case table's order (the CPU reference,
// hemo/reference/marching_cubes.hpp, visits them the same way). A vertex is interpolated
// linearly along its grid edge from the lower to the upper point, so the two voxels sharing
// an edge compute bit-identical vertices. Its normal is minus the field gradient (central
// differences at the edge's two points, one-sided on the grid's faces, interpolated), or the
// triangle's own normal where that gradient vanishes.
#extension GL_GOOGLE_include_directive : require
#include "interface/mc.h"
#include "common/index.glsl"
#include "common/mc.glsl"

layout(std430, binding = HEMO_MC_GENERATE_BINDING_GRID) readonly buffer Grid { McGrid grid; };
layout(std430, binding = HEMO_MC_GENERATE_BINDING_FIELD) readonly buffer Field { int field[]; };
layout(std430, binding = HEMO_MC_GENERATE_BINDING_TABLE) readonly buffer Table { uvec4 table[256]; };
layout(std430, binding = HEMO_MC_GENERATE_BINDING_RUN_TRIANGLES) readonly buffer RunTriangles { uint runTriangles[]; };
layout(std430, binding = HEMO_MC_GENERATE_BINDING_RUN_CASES) readonly buffer RunCases { uint runCases[]; };
layout(std430, binding = HEMO_MC_GENERATE_BINDING_ACTIVE_RUNS) readonly buffer ActiveRuns { uint activeRuns[]; };
layout(std430, binding = HEMO_MC_GENERATE_BINDING_ARGS) readonly buffer Args { uint args[16]; };
layout(std430, binding = HEMO_MC_GENERATE_BINDING_VERTICES) writeonly buffer Vertices { vec4 vertices[]; };
layout(push_constant) uniform Push { uint maxTriangles; } pc;

McGrid g;

float value(uvec3 p) {
  return float(field[hemo_mc_point(p, g)]) * (1.0 / HEMO_MC_FIXED_SCALE);
}

vec3 gradient(uvec3 p) {
  vec3 grad;
  for (int axis = 0; axis < 3; ++axis) {
    uvec3 lo = p, hi = p;
    if (p[axis] > 0u) {
      lo[axis] -= 1u;
    }
    if (p[axis] + 1u < g.points[axis]) {
      hi[axis] += 1u;
    }
    grad[axis] = (value(hi) - value(lo)) / (float(hi[axis] - lo[axis]) * g.origin.w);
  }
  return grad;
}

// Cube edge e (hemo/surface/case_table.hpp): its lower corner and its axis.
uint edge_corner(uint e, out uint axis) {
  if (e < 4u) {
    axis = 0u;
    return 2u * (e & 1u) + 4u * (e >> 1u);
  }
  if (e < 8u) {
    axis = 1u;
    return ((e - 4u) & 1u) + 4u * ((e - 4u) >> 1u);
  }
  axis = 2u;
  return ((e - 8u) & 1u) + 2u * ((e - 8u) >> 1u);
}

uint table_edge(uvec4 entry, uint k) {
  const uint word = k < 8u ? entry.y : (k < 16u ? entry.z : entry.w);
  return (word >> (4u * (k & 7u))) & 15u;
}

void main() {
  const uint a = hemo_global_index();
  if (a >= args[HEMO_MC_ARGS_ACTIVE_RUNS]) {
    return;
  }
  g = grid;
  const uint r = activeRuns[a];
  const uint rx = r % g.runs.x;
  const uint rest = r / g.runs.x;
  const uvec3 runOrigin = uvec3(rx * HEMO_MC_RUN, rest % g.runs.y, rest / g.runs.y);
  const uint cases = runCases[r];
  const float iso = g.level.x;
  uint tri = runTriangles[r];
  for (uint k = 0u; k < HEMO_MC_RUN; ++k) {
    const uint cube = (cases >> (8u * k)) & 255u;
    const uvec4 entry = table[cube];
    const uvec3 voxel = runOrigin + uvec3(k, 0u, 0u);
    for (uint t = 0u; t < entry.x; ++t, ++tri) {
      if (tri >= pc.maxTriangles) {
        return;
      }
      vec3 p[3], n[3];
      for (uint v = 0u; v < 3u; ++v) {
        uint axis;
        const uint corner = edge_corner(table_edge(entry, 3u * t + v), axis);
        const uvec3 pa = voxel + hemo_mc_corner(corner);
        uvec3 pb = pa;
        pb[axis] += 1u;
        const float va = value(pa), vb = value(pb);
        const float s = (iso - va) / (vb - va);
        const vec3 xa = g.origin.xyz + vec3(pa) * g.origin.w;
        const vec3 xb = g.origin.xyz + vec3(pb) * g.origin.w;
        p[v] = xa + s * (xb - xa);
        n[v] = -(gradient(pa) * (1.0 - s) + gradient(pb) * s);
      }
      const vec3 face = cross(p[1] - p[0], p[2] - p[0]);
      const float faceLength = length(face);
      for (uint v = 0u; v < 3u; ++v) {
        const float len = length(n[v]);
        const vec3 normal = len > 1.0e-30 ? n[v] / len : (faceLength > 0.0 ? face / faceLength : vec3(0.0));
        vertices[2u * (3u * tri + v)] = vec4(p[v], 1.0);
        vertices[2u * (3u * tri + v) + 1u] = vec4(normal, 0.0);
      }
    }
  }
}
