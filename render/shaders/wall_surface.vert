#version 450
// The vessel wall as a shaded surface: triangles over the wall points (hemo/sim/wall_surface.hpp),
// three vertices each, their corners found through the id -> slot map and placed along the
// minimum image from the first (a triangle across a periodic seam stays whole). A triangle
// with a broken spring along any edge is clipped away, so the surface tears where the springs
// broke. Each corner carries its particle's wall normal and strain.
// Periodic axes: a triangle across the seam reaches past the domain's box on one side; the
// second instance draws its copy shifted by one period, and the fragment shader keeps each
// copy's part inside the box (other triangles' second instance is clipped away).
#extension GL_GOOGLE_include_directive : require
#include "interface/render.h"
#include "wall/spring.glsl"

layout(std430, set = 0, binding = HEMO_RENDER_SPRINGS_BINDING_POSITIONS) readonly buffer Positions { vec4 positions[]; };
layout(std430, set = 0, binding = HEMO_RENDER_SPRINGS_BINDING_SLOT_OF_ID) readonly buffer SlotOfId { uint slotOfId[]; };
layout(std430, set = 0, binding = HEMO_RENDER_SPRINGS_BINDING_SPRINGS) readonly buffer Springs { Spring springs[]; };
layout(std430, set = 1, binding = HEMO_RENDER_WALL_BINDING_TRIANGLES) readonly buffer Triangles { uint triangles[]; };
layout(std430, set = 1, binding = HEMO_RENDER_WALL_BINDING_NORMALS) readonly buffer Normals { vec4 normals[]; };
layout(std430, set = 1, binding = HEMO_RENDER_WALL_BINDING_SHADE) readonly buffer Shade { vec2 shade[]; };
layout(push_constant) uniform Push {
  mat4 viewProj;
  vec4 period;  // xyz: period (m) on periodic axes, 0 elsewhere; w: strain at the red end
  vec4 origin;  // xyz: the domain's low corner on periodic axes (m); w: opacity
  vec4 eye;     // xyz: camera position (m); w: 1 with the cutaway
  vec4 cut;     // the cutaway's plane: n.x > w is cut away
} pc;

layout(location = 0) out vec3 worldPos;
layout(location = 1) out vec3 worldNormal;
layout(location = 2) out float strain;

void main() {
  const uint base = 6u * (uint(gl_VertexIndex) / 3u);
  const uint corner = uint(gl_VertexIndex) % 3u;
  for (uint e = 0u; e < 3u; ++e) {
    if (springs[triangles[base + 3u + e]].broken != 0u) {
      gl_Position = vec4(0.0, 0.0, 2.0, 1.0);  // beyond the far plane: all three corners, clipped
      worldPos = vec3(0.0);
      worldNormal = vec3(0.0);
      strain = 0.0;
      return;
    }
  }
  const bvec3 periodic = greaterThan(pc.period.xyz, vec3(0.0));
  const vec3 first = positions[slotOfId[triangles[base]]].xyz;
  vec3 corners[3];
  corners[0] = first;
  for (uint c = 1u; c < 3u; ++c) {
    vec3 d = positions[slotOfId[triangles[base + c]]].xyz - first;
    d = mix(d, d - pc.period.xyz * round(d / max(pc.period.xyz, vec3(1.0e-30))), periodic);
    corners[c] = first + d;
  }
  const vec3 lo = min(corners[0], min(corners[1], corners[2]));
  const vec3 hi = max(corners[0], max(corners[1], corners[2]));
  const vec3 top = pc.origin.xyz + pc.period.xyz;
  // The copy's shift: one period back where the triangle reaches past the top of the box, one
  // forward where it reaches below its bottom.
  const vec3 shift = mix(vec3(0.0), -pc.period.xyz * vec3(greaterThanEqual(hi, top)) +
                                        pc.period.xyz * vec3(lessThan(lo, pc.origin.xyz)), periodic);
  if (gl_InstanceIndex == 1 && shift == vec3(0.0)) {
    gl_Position = vec4(0.0, 0.0, 2.0, 1.0);
    worldPos = vec3(0.0);
    worldNormal = vec3(0.0);
    strain = 0.0;
    return;
  }
  const uint slot = slotOfId[triangles[base + corner]];
  worldPos = corners[corner] + (gl_InstanceIndex == 1 ? shift : vec3(0.0));
  worldNormal = normals[slot].xyz;
  strain = shade[slot].x;
  gl_Position = pc.viewProj * vec4(worldPos, 1.0);
}
