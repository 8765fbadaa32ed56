#version 450
// The wall's springs as lines between their end particles (two vertices per spring; the ends
// found through the id -> slot map), coloured by strain: tan at rest length, red at the strain
// scale and beyond. Broken springs are drawn purple when asked, else clipped away. A spring
// across a periodic seam is drawn from its end a along the minimum image.
#extension GL_GOOGLE_include_directive : require
#include "interface/render.h"
#include "wall/spring.glsl"

layout(std430, set = 0, binding = HEMO_RENDER_SPRINGS_BINDING_POSITIONS) readonly buffer Positions { vec4 positions[]; };
layout(std430, set = 0, binding = HEMO_RENDER_SPRINGS_BINDING_SLOT_OF_ID) readonly buffer SlotOfId { uint slotOfId[]; };
layout(std430, set = 0, binding = HEMO_RENDER_SPRINGS_BINDING_SPRINGS) readonly buffer Springs { Spring springs[]; };
layout(push_constant) uniform Push {
  mat4 viewProj;
  vec4 period;  // xyz: period (m) on periodic axes, 0 elsewhere; w: strain at the red end
  uvec4 flags;  // x: draw broken springs
} pc;

layout(location = 0) out vec3 color;

void main() {
  const Spring s = springs[uint(gl_VertexIndex) / 2u];
  const vec3 xa = positions[slotOfId[s.a]].xyz;
  vec3 d = positions[slotOfId[s.b]].xyz - xa;
  d = mix(d, d - pc.period.xyz * round(d / max(pc.period.xyz, vec3(1.0e-30))), greaterThan(pc.period.xyz, vec3(0.0)));
  if (s.broken != 0u && pc.flags.x == 0u) {
    gl_Position = vec4(0.0, 0.0, 2.0, 1.0);  // beyond the far plane: clipped
    color = vec3(0.0);
    return;
  }
  const vec3 x = (gl_VertexIndex & 1) == 0 ? xa : xa + d;
  gl_Position = pc.viewProj * vec4(x, 1.0);
  const float strain = length(d) / s.restLength - 1.0;
  color = s.broken != 0u ? vec3(0.45, 0.12, 0.55)
                         : mix(vec3(0.80, 0.66, 0.50), vec3(0.85, 0.15, 0.05), clamp(strain / pc.period.w, 0.0, 1.0));
}
