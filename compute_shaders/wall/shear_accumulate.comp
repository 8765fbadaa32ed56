#version 450
// The wall shear maps' sums over time, after each step (interface/wall.h, HEMO_SHEARACC_*):
// per wall point id, (sum tau dt, sum |tau| dt) with tau the step's wall shear stress at the
// point's slot (wall/spring_forces.comp) and dt the step's; invocation 0 adds dt to the record
// after the last id's. The time-averaged wall shear stress is sum |tau| dt / sum dt and the
// oscillatory shear index (Ku et al. 1985) 0.5 (1 - |sum tau dt| / sum |tau| dt).
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "interface/wall.h"
#include "common/index.glsl"
#include "common/clock.glsl"

layout(binding = HEMO_SHEARACC_BINDING_IDS_SLOT) uniform usamplerBuffer slotOfIdT;
layout(binding = HEMO_SHEARACC_BINDING_WSS) uniform samplerBuffer wssT;
layout(std140, binding = HEMO_SHEARACC_BINDING_CLOCK) uniform Clock { ClockRecord clocks[2]; };
layout(std430, binding = HEMO_SHEARACC_BINDING_SUMS) buffer Sums { vec4 sums[]; };

layout(push_constant) uniform Push {
  uint idCount;  // wall point ids [0, idCount)
  uint clockIn;  // the record that holds the step just taken
} pc;

void main() {
  const uint id = hemo_global_index();
  // A step past the run's end time changes nothing and leaves the clock as it was (steps
  // not counted): it adds nothing here either.
  const bool stepped = clocks[pc.clockIn].steps != clocks[1u - pc.clockIn].steps;
  const float dt = stepped ? clocks[pc.clockIn].lastDt : 0.0;
  if (id == 0u) {
    sums[pc.idCount].x += dt;
  }
  if (id >= pc.idCount) {
    return;
  }
  const vec3 tau = texelFetch(wssT, int(texelFetch(slotOfIdT, int(id)).x)).xyz;
  sums[id] += vec4(tau * dt, length(tau) * dt);
}
