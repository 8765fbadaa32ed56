#version 450
// The extraction grid's field from a coarser splat grid (same origin; mc/bounds.comp): each
// point takes the trilinear interpolation of the eight splat-grid points around it, rounded to
// fixed point. The particle field is smooth on the scale of h, so a splat grid of h/2 holds it
// well, and the splat (whose cost grows with the cube of h / voxel) gets much cheaper.
#extension GL_GOOGLE_include_directive : require
#include "interface/mc.h"
#include "common/index.glsl"
#include "common/mc.glsl"

layout(std140, binding = HEMO_MC_UPSAMPLE_BINDING_GRID) uniform Grid { McGrid grid; };
layout(std140, binding = HEMO_MC_UPSAMPLE_BINDING_SPLAT_GRID) uniform SplatGrid { McGrid splatGrid; };
// Read-only inputs are uniform texel buffers (see interface/sph.h, "texel slots").
layout(binding = HEMO_MC_UPSAMPLE_BINDING_SPLAT_FIELD) uniform isamplerBuffer coarseT;  // R32_SINT
#define coarse(k) texelFetch(coarseT, int(k)).x
layout(std430, binding = HEMO_MC_UPSAMPLE_BINDING_FIELD) writeonly buffer Field { int field[]; };

void main() {
  const uint i = hemo_global_index();
  const McGrid g = grid;
  if (i >= g.points.x * g.points.y * g.points.z) {
    return;
  }
  const McGrid s = splatGrid;
  const uvec3 p = uvec3(i % g.points.x, (i / g.points.x) % g.points.y, i / (g.points.x * g.points.y));
  // Position in splat-grid units (both grids start at the same origin).
  const vec3 u = vec3(p) * (g.origin.w / s.origin.w);
  const uvec3 hiCell = s.points.xyz - 2u;
  const uvec3 c = min(uvec3(floor(u)), hiCell);
  const vec3 t = clamp(u - vec3(c), 0.0, 1.0);
  const uint row00 = c.x + s.points.w * (c.y + s.points.y * c.z);
  const uint row10 = row00 + s.points.w;                  // y + 1
  const uint row01 = row00 + s.points.w * s.points.y;     // z + 1
  const uint row11 = row01 + s.points.w;                  // y + 1, z + 1
  const float x00 = mix(float(coarse(row00)), float(coarse(row00 + 1u)), t.x);
  const float x10 = mix(float(coarse(row10)), float(coarse(row10 + 1u)), t.x);
  const float x01 = mix(float(coarse(row01)), float(coarse(row01 + 1u)), t.x);
  const float x11 = mix(float(coarse(row11)), float(coarse(row11 + 1u)), t.x);
  const float value = mix(mix(x00, x10, t.y), mix(x01, x11, t.y), t.z);
  field[hemo_mc_point(p, g)] = int(round(value));
}
