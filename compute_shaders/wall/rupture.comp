#version 450
// Rupture: a spring whose tension exceeds its maximum force is flagged broken, for good
// (one invocation per spring; only that invocation writes the flag). The number of broken
// springs is counted with an integer atomic (order-independent).
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "interface/wall.h"
#include "common/index.glsl"
#include "wall/spring.glsl"
#include "common/sph_params.glsl"

// Read-only inputs are uniform texel buffers (interface/sph.h, "texel slots").
layout(binding = HEMO_RUPTURE_BINDING_POSITIONS) uniform samplerBuffer positions;
layout(binding = HEMO_RUPTURE_BINDING_VELOCITIES) uniform samplerBuffer velocities;
layout(binding = HEMO_RUPTURE_BINDING_SLOT_OF_ID) uniform usamplerBuffer slotOfId;
layout(binding = HEMO_RUPTURE_BINDING_SPRINGS_T) uniform usamplerBuffer springsT;  // two uvec4 per Spring
layout(std430, binding = HEMO_RUPTURE_BINDING_SPRINGS) writeonly buffer Springs { Spring springs[]; };
layout(std430, binding = HEMO_RUPTURE_BINDING_COUNTERS) buffer Counters { uint counters[]; };
HEMO_SPH_PARAMS_UNIFORM(HEMO_RUPTURE_BINDING_PARAMS);
layout(push_constant) uniform Push { uint springCount; } pc;

void main() {
  const uint k = hemo_global_index();
  if (k >= pc.springCount) {
    return;
  }
  // spring k's record (interface/wall.h): (a, b, restLength, stiffness), (damping, maxForce, broken, pad)
  const uvec4 t0 = texelFetch(springsT, int(2u * k));
  const uvec4 t1 = texelFetch(springsT, int(2u * k + 1u));
  if (t1.z != 0u) {
    return;  // broken for good
  }
  const int sa = int(texelFetch(slotOfId, int(t0.x)).x);
  const int sb = int(texelFetch(slotOfId, int(t0.y)).x);
  float tension;
  const vec3 delta = hemo_min_image(texelFetch(positions, sb).xyz - texelFetch(positions, sa).xyz, hemo_pair_params());
  hemo_spring_force_on_a(delta, texelFetch(velocities, sa).xyz, texelFetch(velocities, sb).xyz, uintBitsToFloat(t0.z),
                         uintBitsToFloat(t0.w), uintBitsToFloat(t1.x), tension);
  if (tension > uintBitsToFloat(t1.y)) {
    springs[k].broken = 1u;
    atomicAdd(counters[HEMO_WALL_COUNTER_BROKEN], 1u);
  }
}
