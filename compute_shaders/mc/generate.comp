#version 450
// Generate: one invocation per voxel of each active run writes the voxel's triangles at the
// run's scanned offset plus the triangles of the run's voxels before it, so the output is in
// voxel order and in the case table's order (the CPU reference,
// hemo/reference/marching_cubes.hpp, visits them the same way). Per voxel rather than per run:
// a run's triangles are written side by side, not one invocation after another (generate at
// 128^3 on the aneurysm: 11 -> 6.5 ms). A vertex is interpolated
// linearly along its grid edge from the lower to the upper point, so the two voxels sharing
// an edge compute bit-identical vertices. Its normal is minus the field gradient (central
// differences at the edge's two points, one-sided on the grid's faces, interpolated), or the
// triangle's own normal where that gradient vanishes.
#extension GL_GOOGLE_include_directive : require
#include "interface/mc.h"
#include "common/index.glsl"
#include "common/mc.glsl"

layout(std140, binding = HEMO_MC_GENERATE_BINDING_GRID) uniform Grid { McGrid grid; };
// Read-only inputs are uniform texel buffers (see interface/sph.h, "texel slots").
layout(binding = HEMO_MC_GENERATE_BINDING_FIELD) uniform isamplerBuffer field;  // R32_SINT
layout(binding = HEMO_MC_GENERATE_BINDING_TABLE) uniform usamplerBuffer table;  // R32G32B32A32_UINT
layout(binding = HEMO_MC_GENERATE_BINDING_RUN_TRIANGLES) uniform usamplerBuffer runTriangles;
layout(binding = HEMO_MC_GENERATE_BINDING_RUN_CASES) uniform usamplerBuffer runCases;
layout(binding = HEMO_MC_GENERATE_BINDING_ACTIVE_RUNS) uniform usamplerBuffer activeRuns;
layout(std430, binding = HEMO_MC_GENERATE_BINDING_ARGS) readonly buffer Args { uint args[16]; };
layout(std430, binding = HEMO_MC_GENERATE_BINDING_VERTICES) writeonly buffer Vertices { vec4 vertices[]; };
layout(push_constant) uniform Push { uint maxTriangles; } pc;

McGrid g;

float value(uvec3 p) {
  return float(texelFetch(field, int(hemo_mc_point(p, g))).x) * (1.0 / HEMO_MC_FIXED_SCALE);
}

// Central difference at point p (one-sided on the grid's faces), in field units per m.
// Written out per axis: dynamically indexed vectors and arrays cost memory round trips on
// llvmpipe.
vec3 gradient(uvec3 p) {
  const uvec3 lo = uvec3(max(ivec3(p) - 1, ivec3(0)));
  const uvec3 hi = min(p + 1u, g.points.xyz - 1u);
  const vec3 span = vec3(hi - lo) * g.origin.w;
  return vec3((value(uvec3(hi.x, p.y, p.z)) - value(uvec3(lo.x, p.y, p.z))) / span.x,
              (value(uvec3(p.x, hi.y, p.z)) - value(uvec3(p.x, lo.y, p.z))) / span.y,
              (value(uvec3(p.x, p.y, hi.z)) - value(uvec3(p.x, p.y, lo.z))) / span.z);
}

// The vertex on cube edge e of `voxel`: position (m) and minus the interpolated gradient.
void edge_vertex(uvec3 voxel, uint e, float iso, out vec3 position, out vec3 normal) {
  // Edge e (hemo/surface/case_table.hpp): lower corner and axis.
  uvec3 pa, step;
  if (e < 4u) {
    pa = voxel + uvec3(0u, e & 1u, e >> 1u);
    step = uvec3(1u, 0u, 0u);
  } else if (e < 8u) {
    pa = voxel + uvec3((e - 4u) & 1u, 0u, (e - 4u) >> 1u);
    step = uvec3(0u, 1u, 0u);
  } else {
    pa = voxel + uvec3((e - 8u) & 1u, (e - 8u) >> 1u, 0u);
    step = uvec3(0u, 0u, 1u);
  }
  const uvec3 pb = pa + step;
  const float va = value(pa), vb = value(pb);
  const float s = (iso - va) / (vb - va);
  const vec3 xa = g.origin.xyz + vec3(pa) * g.origin.w;
  const vec3 xb = g.origin.xyz + vec3(pb) * g.origin.w;
  position = xa + s * (xb - xa);
  normal = -(gradient(pa) * (1.0 - s) + gradient(pb) * s);
}

vec3 unit_or(vec3 n, vec3 fallback) {
  const float len = length(n);
  return len > 1.0e-30 ? n / len : fallback;
}

uint table_edge(uvec4 entry, uint k) {
  const uint word = k < 8u ? entry.y : (k < 16u ? entry.z : entry.w);
  return (word >> (4u * (k & 7u))) & 15u;
}

void main() {
  // One invocation per voxel of an active run: HEMO_MC_RUN per run, so a run's triangles are
  // written by several invocations side by side rather than one after another.
  const uint index = hemo_global_index();
  const uint a = index / HEMO_MC_RUN;
  const uint k = index % HEMO_MC_RUN;
  if (a >= args[HEMO_MC_ARGS_ACTIVE_RUNS]) {
    return;
  }
  const uint r = texelFetch(activeRuns, int(a)).x;
  const uint cases = texelFetch(runCases, int(r)).x;
  const uint cube = (cases >> (8u * k)) & 255u;
  if (cube == 0u || cube == 255u) {
    return;
  }
  g = grid;
  const uint rx = r % g.runs.x;
  const uint rest = r / g.runs.x;
  const uvec3 voxel = uvec3(rx * HEMO_MC_RUN + k, rest % g.runs.y, rest / g.runs.y);
  const float iso = g.level.x;
  // This voxel's first triangle: the run's offset plus the voxels before it in the run.
  uint tri = texelFetch(runTriangles, int(r)).x;
  for (uint j = 0u; j < k; ++j) {
    tri += texelFetch(table, int((cases >> (8u * j)) & 255u)).x;
  }
  const uvec4 entry = texelFetch(table, int(cube));
  for (uint t = 0u; t < entry.x; ++t, ++tri) {
    if (tri >= pc.maxTriangles) {
      return;
    }
    vec3 p0, p1, p2, n0, n1, n2;
    edge_vertex(voxel, table_edge(entry, 3u * t), iso, p0, n0);
    edge_vertex(voxel, table_edge(entry, 3u * t + 1u), iso, p1, n1);
    edge_vertex(voxel, table_edge(entry, 3u * t + 2u), iso, p2, n2);
    const vec3 face = unit_or(cross(p1 - p0, p2 - p0), vec3(0.0));
    const uint base = 6u * tri;
    vertices[base + 0u] = vec4(p0, 1.0);
    vertices[base + 1u] = vec4(unit_or(n0, face), 0.0);
    vertices[base + 2u] = vec4(p1, 1.0);
    vertices[base + 3u] = vec4(unit_or(n1, face), 0.0);
    vertices[base + 4u] = vec4(p2, 1.0);
    vertices[base + 5u] = vec4(unit_or(n2, face), 0.0);
  }
}
