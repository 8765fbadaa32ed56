#version 450
// The grid the blood surface is extracted on: the bounding box of the finite fluid particles,
// grown by `margin` on every side (the field's support, so the surface closes inside the
// grid) and clipped to a region of interest (particles that fly far away would otherwise
// stretch the grid and coarsen the voxels), cut into cubic voxels with `resolution` voxels along its longest side. One workgroup
// reduces the box (min and max are exact, so the order does not matter) and invocation 0
// writes origin, voxel size and point counts, and the splat's dispatch: one invocation per
// (fluid-or-not particle, z-plane of its support). The voxel is never finer than margin / 126
// (h / 63): then a particle's support spans at most 254 planes and an invocation's loop over
// one plane at most 254^2 points. (llvmpipe stops any shader invocation after 65,535 loop
// iterations in total; a particle's whole support in one invocation silently lost most of
// its contributions on fine grids.) No fluid: zero points, nothing extracted.
#extension GL_GOOGLE_include_directive : require
#include "interface/mc.h"
#include "interface/sph.h"
#include "common/index.glsl"
#include "common/mc.glsl"

layout(std430, binding = HEMO_MC_BOUNDS_BINDING_POSITIONS) readonly buffer Positions { vec4 positions[]; };
layout(std430, binding = HEMO_MC_BOUNDS_BINDING_VELOCITIES) readonly buffer Velocities { vec4 velocities[]; };
layout(std430, binding = HEMO_MC_BOUNDS_BINDING_GRID) writeonly buffer Grid { McGrid grid; };
layout(std430, binding = HEMO_MC_BOUNDS_BINDING_SPLAT_ARGS) writeonly buffer SplatArgs { uint splatArgs[4]; };
layout(push_constant) uniform Push {
  uint n;
  uint resolution;
  float margin;  // the field's support radius 2h (m)
  float iso;
  uint splatWorkgroup;
  uint pad0, pad1, pad2;
  vec4 clipLo;  // xyz: the grid never extends below this (m)
  vec4 clipHi;  // xyz: ... nor above this
} pc;

shared vec3 s_lo[gl_WorkGroupSize.x];
shared vec3 s_hi[gl_WorkGroupSize.x];

void main() {
  const uint lane = gl_LocalInvocationID.x;
  vec3 lo = vec3(3.0e38), hi = vec3(-3.0e38);
  for (uint i = lane; i < pc.n; i += gl_WorkGroupSize.x) {
    if (uint(velocities[i].w) != HEMO_KIND_FLUID) {
      continue;
    }
    const vec3 p = positions[i].xyz;
    if (any(isnan(p)) || any(isinf(p))) {
      continue;
    }
    lo = min(lo, p);
    hi = max(hi, p);
  }
  s_lo[lane] = lo;
  s_hi[lane] = hi;
  barrier();
  for (uint stride = gl_WorkGroupSize.x / 2u; stride > 0u; stride /= 2u) {
    if (lane < stride) {
      s_lo[lane] = min(s_lo[lane], s_lo[lane + stride]);
      s_hi[lane] = max(s_hi[lane], s_hi[lane + stride]);
    }
    barrier();
  }
  if (lane != 0u) {
    return;
  }
  lo = s_lo[0];
  hi = s_hi[0];
  if (any(greaterThan(lo, hi))) {
    grid.origin = vec4(0.0, 0.0, 0.0, 1.0);
    grid.points = uvec4(0u);
    grid.runs = uvec4(0u);
    grid.level = vec4(pc.iso, 0.0, 0.0, 0.0);
    splatArgs[0] = 0u;
    splatArgs[1] = 0u;
    splatArgs[2] = 0u;
    return;
  }
  lo = max(lo - vec3(pc.margin), pc.clipLo.xyz);
  hi = min(hi + vec3(pc.margin), pc.clipHi.xyz);
  if (any(greaterThanEqual(lo, hi))) {
    grid.origin = vec4(0.0, 0.0, 0.0, 1.0);
    grid.points = uvec4(0u);
    grid.runs = uvec4(0u);
    grid.level = vec4(pc.iso, 0.0, 0.0, 0.0);
    splatArgs[0] = 0u;
    splatArgs[1] = 0u;
    splatArgs[2] = 0u;
    return;
  }
  const vec3 extent = hi - lo;
  const float voxel = max(max(extent.x, max(extent.y, extent.z)) / float(pc.resolution), pc.margin / 126.0);
  // Enough voxels to cover the extent, never more than the resolution (rounding).
  const uvec3 voxels = min(uvec3(ceil(extent / voxel)), uvec3(pc.resolution));
  const uvec3 points = max(voxels, uvec3(1u)) + 1u;
  grid.origin = vec4(lo, voxel);
  grid.points = uvec4(points, hemo_mc_row_stride(points.x));
  grid.runs = uvec4(0u);
  // z-planes a support of radius `margin` can touch, and one invocation per (slot, plane).
  const uint planes = 2u * uint(floor(pc.margin / voxel)) + 2u;
  grid.level = vec4(pc.iso, float(planes), 0.0, 0.0);
  const uvec3 groups = hemo_mc_groups(pc.n * planes, pc.splatWorkgroup);
  splatArgs[0] = groups.x;
  splatArgs[1] = groups.y;
  splatArgs[2] = groups.z;
}
