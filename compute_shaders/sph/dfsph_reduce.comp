#version 450
// DFSPH's convergence test (interface/sph.h, "The pressure solver"), one workgroup: the mean
// compression of the last prediction over the fluid, from sph/dfsph_predict.comp's
// fixed-point partials (summed as 64-bit integers, so in any order to the same bits), and the
// decision on the next gated region (a correction and the prediction after it): open while the
// mean exceeds the tolerance, or fewer than the solve's minimum corrections have run, and the
// cap allows another correction. The region it closes runs
// no workgroups, and the reductions after it find the solve inactive and keep it closed.
// The stats (HEMO_DFSPH_STAT_*) count what the solves did, for the host to read after a batch.
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "common/index.glsl"

layout(std430, binding = HEMO_DFSPH_REDUCE_BINDING_PARTIALS) readonly buffer Partials { uint partials[]; };
layout(std430, binding = HEMO_DFSPH_REDUCE_BINDING_STATS) buffer Stats { uint statWords[2 * HEMO_DFSPH_STAT_COUNT]; };
#define stats(k) statWords[pc.statBase + (k)]
layout(std430, binding = HEMO_DFSPH_REDUCE_BINDING_ARMED) readonly buffer Armed { uvec4 gateArmed[]; };
layout(std430, binding = HEMO_DFSPH_REDUCE_BINDING_ARGS) writeonly buffer Args { uvec4 gateArgs[]; };
layout(std430, binding = HEMO_DFSPH_REDUCE_BINDING_OPENED) buffer Opened { uint gateOpened; };
layout(std430, binding = HEMO_DFSPH_REDUCE_BINDING_DEPTH) buffer Depth { uint depth[HEMO_DFSPH_DEPTH_COUNT]; };
layout(push_constant) uniform Push {
  uint partialCount;   // the prediction's workgroups
  uint fluid;          // fluid particles (the mean's divisor)
  uint iteration;      // 0: the step's first prediction; k: the one after correction k
  uint maxIterations;  // the cap on corrections
  float tolerance;     // of the mean compression, / rho0
  uint slots;          // the gate's slots
  uint statBase;       // the solve's stats: 0 density, HEMO_DFSPH_STAT_COUNT divergence
  uint recorded;       // the gated regions the host recorded after this solve's first prediction
  uint minIterations;  // corrections run even where the mean is within the tolerance
} pc;

#include "common/gate.glsl"

shared uvec2 s_sum[gl_WorkGroupSize.x];  // (low, high) words
shared bool s_open;

uvec2 add64(uvec2 a, uvec2 b) {
  uint carry;
  const uint low = uaddCarry(a.x, b.x, carry);
  return uvec2(low, a.y + b.y + carry);
}

void main() {
  const uint lid = gl_LocalInvocationID.x;
  // (a reduction whose solve already ended reads nothing: its prediction did not run)
  const bool running = pc.iteration == 0u || stats(HEMO_DFSPH_STAT_ACTIVE) != 0u;
  uvec2 sum = uvec2(0u);
  if (running) {
    for (uint p = lid; p < pc.partialCount; p += gl_WorkGroupSize.x) {
      sum = add64(sum, uvec2(partials[p], 0u));
    }
  }
  s_sum[lid] = sum;
  barrier();
  // Halving the sums in shared memory (integers: any order gives the same bits).
  for (uint width = gl_WorkGroupSize.x; width > 1u;) {
    const uint upper = (width + 1u) / 2u;
    if (lid < width - upper) {
      s_sum[lid] = add64(s_sum[lid], s_sum[lid + upper]);
    }
    barrier();
    width = upper;
  }
  bool open = false;
  if (running && lid == 0u) {
    const uvec2 total = s_sum[0];
    const float error = (float(total.y) * 4294967296.0 + float(total.x)) / HEMO_DFSPH_ERROR_SCALE / float(max(pc.fluid, 1u));
    const bool converged = error <= pc.tolerance;
    if (pc.iteration == 0u) {
      stats(HEMO_DFSPH_STAT_ITERATIONS) = 0u;
    }
    stats(HEMO_DFSPH_STAT_ERROR) = floatBitsToUint(error);
    open = (!converged || pc.iteration < pc.minIterations) && pc.iteration < pc.maxIterations;
    if (open) {
      stats(HEMO_DFSPH_STAT_ITERATIONS) += 1u;
      stats(HEMO_DFSPH_STAT_TOTAL) += 1u;
      stats(HEMO_DFSPH_STAT_ACTIVE) = 1u;
      // No region follows the last recorded one: the batch is run again, recorded deeper.
      if (pc.iteration >= pc.recorded) {
        depth[HEMO_DFSPH_DEPTH_DEEPER] += 1u;
      }
    } else {
      depth[HEMO_DFSPH_DEPTH_MAX] = max(depth[HEMO_DFSPH_DEPTH_MAX], stats(HEMO_DFSPH_STAT_ITERATIONS));
      stats(HEMO_DFSPH_STAT_ACTIVE) = 0u;
      stats(HEMO_DFSPH_STAT_SOLVES) += 1u;
      stats(HEMO_DFSPH_STAT_CAP_HITS) += converged ? 0u : 1u;
      stats(HEMO_DFSPH_STAT_MAX) = max(stats(HEMO_DFSPH_STAT_MAX), stats(HEMO_DFSPH_STAT_ITERATIONS));
      // (a NaN error compares false: max keeps the old value, and NaN wins as a larger one)
      const float worst = uintBitsToFloat(stats(HEMO_DFSPH_STAT_WORST_ERROR));
      stats(HEMO_DFSPH_STAT_WORST_ERROR) = floatBitsToUint(isnan(error) || error > worst ? error : worst);
    }
  }
  if (lid == 0u) {
    s_open = open;
  }
  barrier();
  hemo_gate_arm(s_open, pc.slots);
}
