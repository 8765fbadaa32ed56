#version 450
// The reach of every slot for the neighbour-list rebuild test (after the integrator and the
// (min, max) reduction of its x displacements since the list build):
//   reach = |d - (c, 0, 0)|,  c = (min d.x + max d.x) / 2,
// plus, when the next step evaluates forces at a midpoint, the farthest the next half step
// can take the particle, |v| min(dtMax, C_a h / (c0 + |v|)) / 2.
// Any common vector c keeps the test valid: two particles' separation has changed by
// |d_i - d_j| <= |d_i - c| + |d_j - c| <= 2 max reach, so the list holds every pair within
// the support while the largest reach stays under half the skin (the step's gate). Taking c
// in the middle of the flow's displacements halves the reach of a uniform or parabolic drift
// along x (a vessel's axis), which does not change who neighbours whom.
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "common/index.glsl"
#include "common/sph_params.glsl"

// Read-only inputs are uniform texel buffers (interface/sph.h, "texel slots").
layout(binding = HEMO_REACH_BINDING_POSITIONS) uniform samplerBuffer positions;
layout(binding = HEMO_REACH_BINDING_VELOCITIES) uniform samplerBuffer velocities;
layout(binding = HEMO_REACH_BINDING_POS_AT_BUILD) uniform samplerBuffer posAtBuild;
HEMO_SPH_PARAMS_UNIFORM(HEMO_REACH_BINDING_PARAMS);
layout(std140, binding = HEMO_REACH_BINDING_DRIFT_RANGE) uniform DriftRange { vec2 driftRange; };
layout(std430, binding = HEMO_REACH_BINDING_REACH) writeonly buffer Reach { float reach[]; };
layout(push_constant) uniform Push {
  uint n;
  uint midpointLookahead;
} pc;

void main() {
  const uint i = hemo_global_index();
  if (i >= pc.n) {
    return;
  }
  float c = 0.5 * (driftRange.x + driftRange.y);
  if (!(abs(c) < 1.0e30)) {
    c = 0.0;  // NaN (a non-finite particle, whose own reach is NaN and opens the gate) or none
  }
  const vec3 d = hemo_min_image(texelFetch(positions, int(i)).xyz - texelFetch(posAtBuild, int(i)).xyz, hemo_pair_params());
  float r = length(d - vec3(c, 0.0, 0.0));
  if (pc.midpointLookahead != 0u) {
    const float speed = length(texelFetch(velocities, int(i)).xyz);
    r += 0.5 * speed * min(params.dtMax, params.cflAcoustic * params.h / (params.c0 + speed));
  }
  reach[i] = r;
}
