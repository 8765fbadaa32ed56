#version 450
// Particles as camera-facing discs: one instance per particle slot, six vertices (two
// triangles) per instance; position and kind come straight from the engine's buffers.
// Fluid is coloured by speed; wall particles by the strain of their springs (tan at rest,
// orange-red when stretched) and marked purple as their springs break (wall/point_shade.comp);
// rigid boundary particles grey. Kinds not
// shown (and non-finite positions) are moved beyond the far plane and clipped. A cutaway
// plane hides the wall and boundary particles in front of it, so the blood inside a vessel
// or a tank shows.
#extension GL_GOOGLE_include_directive : require
#include "interface/render.h"
#include "interface/sph.h"

layout(std430, set = 0, binding = HEMO_RENDER_BINDING_POSITIONS) readonly buffer Positions { vec4 positions[]; };
layout(std430, set = 0, binding = HEMO_RENDER_BINDING_VELOCITIES) readonly buffer Velocities { vec4 velocities[]; };
layout(std430, set = 0, binding = HEMO_RENDER_BINDING_WALL_SHADE) readonly buffer WallShade { vec2 wallShade[]; };
layout(push_constant) uniform Push {
  mat4 viewProj;
  vec4 right;  // xyz: camera right (unit); w: disc radius (m)
  vec4 up;     // xyz: camera up (unit); w: speed (m/s) at the top of the colour scale
  uvec4 show;  // x: fluid, y: wall, z: boundary; w: float bits of the strain at the red end
               // of the wall's scale (0: no wall shade buffer, plain wall colour)
  vec4 cut;    // wall and boundary particles with dot(cut.xyz, x) > cut.w are hidden (cut.xyz = 0: none)
} pc;

layout(location = 0) out vec2 corner;
layout(location = 1) out vec3 color;

const vec2 kCorners[6] = vec2[](vec2(-1.0, -1.0), vec2(1.0, -1.0), vec2(1.0, 1.0),
                                vec2(-1.0, -1.0), vec2(1.0, 1.0), vec2(-1.0, 1.0));

// Blue (slow) -> cyan -> yellow -> red (fast), piecewise linear in s in [0, 1].
vec3 speed_color(float s) {
  s = clamp(s, 0.0, 1.0);
  if (s < 1.0 / 3.0) {
    return mix(vec3(0.10, 0.25, 0.90), vec3(0.10, 0.85, 0.90), 3.0 * s);
  }
  if (s < 2.0 / 3.0) {
    return mix(vec3(0.10, 0.85, 0.90), vec3(0.95, 0.90, 0.15), 3.0 * s - 1.0);
  }
  return mix(vec3(0.95, 0.90, 0.15), vec3(0.90, 0.15, 0.10), 3.0 * s - 2.0);
}

void main() {
  const vec4 p = positions[gl_InstanceIndex];
  const vec4 v = velocities[gl_InstanceIndex];
  const uint kind = uint(v.w);
  const bool cutAway = kind != HEMO_KIND_FLUID && dot(pc.cut.xyz, p.xyz) > pc.cut.w;
  // (a parked slot of open vessel ends holds no particle: interface/sph.h)
  const bool shown = !cutAway && kind != HEMO_KIND_PARKED && (kind == HEMO_KIND_FLUID ? pc.show.x != 0u
                                  : (kind == HEMO_KIND_WALL ? pc.show.y != 0u : pc.show.z != 0u));
  corner = kCorners[gl_VertexIndex];
  if (!shown || any(isnan(p.xyz)) || any(isinf(p.xyz))) {
    gl_Position = vec4(0.0, 0.0, 2.0, 1.0);
    color = vec3(0.0);
    return;
  }
  const vec3 world = p.xyz + (corner.x * pc.right.xyz + corner.y * pc.up.xyz) * pc.right.w;
  gl_Position = pc.viewProj * vec4(world, 1.0);
  if (kind == HEMO_KIND_FLUID) {
    color = speed_color(length(v.xyz) / pc.up.w);
  } else if (kind == HEMO_KIND_WALL) {
    color = vec3(0.86, 0.72, 0.58);
    const float strainScale = uintBitsToFloat(pc.show.w);
    if (strainScale > 0.0) {
      const vec2 shade = wallShade[gl_InstanceIndex];
      color = mix(color, vec3(0.85, 0.22, 0.08), clamp(shade.x / strainScale, 0.0, 1.0));
      color = mix(color, vec3(0.35, 0.10, 0.45), clamp(shade.y, 0.0, 1.0));
    }
  } else {
    color = vec3(0.55);
  }
}
