#version 450
// What the renderer colours wall particles by: per particle slot, vec2(largest strain of its
// unbroken springs (|x_b - x_a| / rest - 1, minimum image on periodic axes; 0 when all are
// compressed or broken), fraction of its springs that broke); vec2(0) for other kinds. A
// gather over the particle's springs (CSR by id), like wall/spring_forces.comp. The CPU twin
// is io::wallPointStats. The first component is instead, by push.mode (hemo/sim/wall.hpp,
// MassSpring::ShadeBy): 1 the particle's wall shear stress (|tau|, Pa, the last force pass's),
// 2 its time average (sum |tau| dt / sum dt, Pa; wall/shear_accumulate.comp), 3 its oscillatory
// shear index (1 - |sum tau dt| / sum |tau| dt) / 2, 4 its pressure (Pa, the last density and
// boundary passes'), 5 the fraction of its springs broken.
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "interface/wall.h"
#include "common/index.glsl"
#include "wall/spring.glsl"
#include "common/sph_params.glsl"

layout(std430, binding = HEMO_SHADE_BINDING_POSITIONS) readonly buffer Positions { vec4 positions[]; };
layout(std430, binding = HEMO_SHADE_BINDING_VELOCITIES) readonly buffer Velocities { vec4 velocities[]; };
layout(std430, binding = HEMO_SHADE_BINDING_IDS) readonly buffer Ids { uint ids[]; };
layout(std430, binding = HEMO_SHADE_BINDING_SLOT_OF_ID) readonly buffer SlotOfId { uint slotOfId[]; };
layout(std430, binding = HEMO_SHADE_BINDING_SPRINGS) readonly buffer Springs { Spring springs[]; };
layout(std430, binding = HEMO_SHADE_BINDING_FIRST) readonly buffer First { uint first[]; };
layout(std430, binding = HEMO_SHADE_BINDING_SPRINGS_OF) readonly buffer SpringsOf { uint springsOf[]; };
HEMO_SPH_PARAMS_UNIFORM(HEMO_SHADE_BINDING_PARAMS);
layout(std430, binding = HEMO_SHADE_BINDING_SHADE) writeonly buffer Shade { vec2 shade[]; };
layout(std430, binding = HEMO_SHADE_BINDING_WSS) readonly buffer Wss { vec4 wss[]; };
layout(std430, binding = HEMO_SHADE_BINDING_SHEAR_SUMS) readonly buffer ShearSums { vec4 shearSums[]; };
layout(std430, binding = HEMO_SHADE_BINDING_STATE) readonly buffer State { vec4 state[]; };  // (rho, p, ...) per slot
layout(push_constant) uniform Push {
  uint n;
  uint idCount;
  uint mode;  // 0 strain, 1 wall shear stress, 2 its time average, 3 OSI, 4 pressure, 5 broken fraction
} pc;

void main() {
  const uint i = hemo_global_index();
  if (i >= pc.n) {
    return;
  }
  const uint id = ids[i];
  if (uint(velocities[i].w) != HEMO_KIND_WALL || id >= pc.idCount) {
    shade[i] = vec2(0.0);
    return;
  }
  const HemoPairParams pp = hemo_pair_params();
  float strain = 0.0;
  uint total = 0u, broken = 0u;
  for (uint k = first[id]; k < first[id + 1u]; ++k) {
    const Spring s = springs[springsOf[k]];
    ++total;
    if (s.broken != 0u) {
      ++broken;
      continue;
    }
    const vec3 delta = hemo_min_image(positions[slotOfId[s.b]].xyz - positions[slotOfId[s.a]].xyz, pp);
    strain = max(strain, length(delta) / s.restLength - 1.0);
  }
  const float brokenFraction = total > 0u ? float(broken) / float(total) : 0.0;
  float value = strain;
  if (pc.mode == 1u) {
    value = length(wss[i].xyz);
  } else if (pc.mode == 2u) {
    const float seconds = shearSums[pc.idCount].x;
    value = seconds > 0.0 ? shearSums[id].w / seconds : 0.0;
  } else if (pc.mode == 3u) {
    const vec4 sum = shearSums[id];
    value = sum.w > 0.0 ? 0.5 * (1.0 - min(length(sum.xyz) / sum.w, 1.0)) : 0.0;
  } else if (pc.mode == 4u) {
    value = state[i].y;
  } else if (pc.mode == 5u) {
    value = brokenFraction;
  }
  shade[i] = vec2(value, brokenFraction);
}
