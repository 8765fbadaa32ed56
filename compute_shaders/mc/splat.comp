#version 450
// The particle field on the surface grid, by a deterministic splat: every fluid particle j
// adds its share of the SPH volume-fraction estimate
//   phi(x) = sum_j (m_j / rho_j) W(|x - x_j|, h)      (Wendland C2, support 2h)
// to the grid points within its support, rounded to fixed point (interface/mc.h) and added
// with integer atomics. Integer sums do not depend on the order of the additions, so the
// field is bit-identical from run to run. phi is about 1 inside the fluid, 0 far from it and
// about 1/2 at the free surface. The field must be zeroed before (a buffer fill).
// One invocation per (particle slot, z-plane of its support): mc/bounds.comp sizes the
// dispatch so that no invocation loops over more than 254^2 points (llvmpipe's limit on a
// shader invocation's loop iterations is 65,535).
#extension GL_GOOGLE_include_directive : require
#include "interface/mc.h"
#include "interface/sph.h"
#include "common/index.glsl"
#include "common/kernel.glsl"
#include "common/mc.glsl"

// Read-only inputs are uniform texel buffers (see interface/sph.h, "texel slots").
layout(binding = HEMO_MC_SPLAT_BINDING_POSITIONS) uniform samplerBuffer positions;
layout(binding = HEMO_MC_SPLAT_BINDING_VELOCITIES) uniform samplerBuffer velocities;
layout(binding = HEMO_MC_SPLAT_BINDING_STATE) uniform samplerBuffer state;
layout(std140, binding = HEMO_MC_SPLAT_BINDING_GRID) uniform Grid { McGrid grid; };
layout(std430, binding = HEMO_MC_SPLAT_BINDING_FIELD) buffer Field { int field[]; };
layout(push_constant) uniform Push {
  uint n;
  float h;
  float kernelNorm;
  float rho0;
} pc;

void main() {
  const uint planes = uint(grid.level.y);
  const uint invocation = hemo_global_index();
  const uint i = invocation / max(planes, 1u);
  if (i >= pc.n || uint(texelFetch(velocities, int(i)).w) != HEMO_KIND_FLUID) {
    return;
  }
  const vec4 p = texelFetch(positions, int(i));
  if (any(isnan(p.xyz)) || any(isinf(p.xyz))) {
    return;
  }
  const McGrid g = grid;
  if (g.points.x == 0u) {
    return;
  }
  const float rho = texelFetch(state, int(i)).x;
  const float volume = p.w / (rho > 0.0 ? rho : pc.rho0);
  const float support = 2.0 * pc.h;
  const float voxel = g.origin.w;
  const vec3 rel = p.xyz - g.origin.xyz;
  const vec3 hiPoint = vec3(g.points.xyz - 1u);
  const vec3 first = clamp(ceil((rel - support) / voxel), vec3(0.0), hiPoint);
  const vec3 last = clamp(floor((rel + support) / voxel), vec3(0.0), hiPoint);
  if (any(greaterThan(first, last))) {
    return;
  }
  const uvec3 a = uvec3(first), b = uvec3(last);
  const float support2 = support * support;
  const uint z = a.z + invocation % planes;
  if (z > b.z) {
    return;
  }
  // Only the rows and, in each row, the points the support sphere covers.
  const float dz = float(z) * voxel - rel.z;
  const float planeRadius2 = support2 - dz * dz;
  if (planeRadius2 <= 0.0) {
    return;
  }
  const float planeRadius = sqrt(planeRadius2);
  const float y0 = max(ceil((rel.y - planeRadius) / voxel), float(a.y));
  const float y1 = min(floor((rel.y + planeRadius) / voxel), float(b.y));
  if (y1 < y0) {
    return;
  }
  for (uint y = uint(y0); y <= uint(y1); ++y) {
    const float dy = float(y) * voxel - rel.y;
    const float ryz2 = dy * dy + dz * dz;
    const float chord2 = support2 - ryz2;
    if (chord2 <= 0.0) {
      continue;
    }
    const float chord = sqrt(chord2);
    const float x0 = max(ceil((rel.x - chord) / voxel), float(a.x));
    const float x1 = min(floor((rel.x + chord) / voxel), float(b.x));
    if (x1 < x0) {
      continue;
    }
    const uint row = g.points.w * (y + g.points.y * z);
    for (uint x = uint(x0); x <= uint(x1); ++x) {
      const float dx = float(x) * voxel - rel.x;
      const float r2 = ryz2 + dx * dx;
      if (r2 < support2) {
        const int add = int(round(volume * hemo_kernel_w(sqrt(r2), pc.h, pc.kernelNorm) * HEMO_MC_FIXED_SCALE));
        if (add != 0) {
          atomicAdd(field[row + x], add);
        }
      }
    }
  }
}
