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

// Read-only inputs are uniform texel buffers (see interface/sph.h, "texel slots").
layout(binding = HEMO_MC_BOUNDS_BINDING_POSITIONS) uniform samplerBuffer positions;
layout(binding = HEMO_MC_BOUNDS_BINDING_VELOCITIES) uniform samplerBuffer velocities;
layout(std430, binding = HEMO_MC_BOUNDS_BINDING_GRID) writeonly buffer Grid { McGrid grid; };
layout(std430, binding = HEMO_MC_BOUNDS_BINDING_SPLAT_ARGS) writeonly buffer SplatArgs { uint splatArgs[4]; };
layout(std430, binding = HEMO_MC_BOUNDS_BINDING_SPLAT_GRID) writeonly buffer SplatGrid { McGrid splatGrid; };
layout(std430, binding = HEMO_MC_BOUNDS_BINDING_UPSAMPLE_ARGS) writeonly buffer UpsampleArgs { uint upsampleArgs[4]; };
layout(push_constant) uniform Push {
  uint n;
  uint resolution;
  float margin;  // the field's support radius 2h (m)
  float iso;
  uint splatWorkgroup;
  float splatVoxel;  // > 0: splat on a coarser grid of about this voxel (m), then upsample
  uint upsampleWorkgroup;
  uint pad0;
  vec4 clipLo;  // xyz: the grid never extends below this (m)
  vec4 clipHi;  // xyz: ... nor above this
} pc;

shared vec3 s_lo[gl_WorkGroupSize.x];
shared vec3 s_hi[gl_WorkGroupSize.x];

void empty_grids() {
  McGrid e;
  e.origin = vec4(0.0, 0.0, 0.0, 1.0);
  e.points = uvec4(0u);
  e.runs = uvec4(0u);
  e.level = vec4(pc.iso, 0.0, 0.0, 0.0);
  grid = e;
  splatGrid = e;
  for (uint k = 0u; k < 4u; ++k) {
    splatArgs[k] = 0u;
    upsampleArgs[k] = 0u;
  }
}

void main() {
  const uint lane = gl_LocalInvocationID.x;
  vec3 lo = vec3(3.0e38), hi = vec3(-3.0e38);
  for (uint i = lane; i < pc.n; i += gl_WorkGroupSize.x) {
    if (uint(texelFetch(velocities, int(i)).w) != HEMO_KIND_FLUID) {
      continue;
    }
    const vec3 p = texelFetch(positions, int(i)).xyz;
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
    empty_grids();
    return;
  }
  lo = max(lo - vec3(pc.margin), pc.clipLo.xyz);
  hi = min(hi + vec3(pc.margin), pc.clipHi.xyz);
  if (any(greaterThanEqual(lo, hi))) {
    empty_grids();
    return;
  }
  const vec3 extent = hi - lo;
  const float voxel = max(max(extent.x, max(extent.y, extent.z)) / float(pc.resolution), pc.margin / 126.0);
  // Enough voxels to cover the extent, never more than the resolution (rounding).
  const uvec3 voxels = min(uvec3(ceil(extent / voxel)), uvec3(pc.resolution));
  const uvec3 points = max(voxels, uvec3(1u)) + 1u;
  McGrid g;
  g.origin = vec4(lo, voxel);
  g.points = uvec4(points, hemo_mc_row_stride(points.x));
  g.runs = uvec4(0u);
  // The splat's grid: the extraction grid itself, or (splatVoxel > 0) one of coarser voxels
  // from the same origin, one point beyond the extraction grid's far corner on each axis;
  // mc/upsample.comp then interpolates the extraction grid's values from it.
  McGrid s = g;
  if (pc.splatVoxel > 0.0) {
    const float coarse = max(pc.splatVoxel, voxel);
    const uvec3 coarsePoints = uvec3(ceil(vec3(points - 1u) * voxel / coarse)) + 2u;
    s.origin = vec4(lo, coarse);
    s.points = uvec4(coarsePoints, hemo_mc_row_stride(coarsePoints.x));
    const uvec3 up = hemo_mc_groups(points.x * points.y * points.z, pc.upsampleWorkgroup);
    upsampleArgs[0] = up.x;
    upsampleArgs[1] = up.y;
    upsampleArgs[2] = up.z;
  } else {
    upsampleArgs[0] = 0u;
    upsampleArgs[1] = 0u;
    upsampleArgs[2] = 0u;
  }
  // z-planes a support of radius `margin` can touch, and one invocation per (slot, plane).
  const uint planes = 2u * uint(floor(pc.margin / s.origin.w)) + 2u;
  s.level = vec4(pc.iso, float(planes), 0.0, 0.0);
  g.level = vec4(pc.iso, float(planes), 0.0, 0.0);
  grid = g;
  splatGrid = s;
  const uvec3 groups = hemo_mc_groups(pc.n * planes, pc.splatWorkgroup);
  splatArgs[0] = groups.x;
  splatArgs[1] = groups.y;
  splatArgs[2] = groups.z;
}
