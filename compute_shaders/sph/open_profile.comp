#version 450
// The pressure ends' velocity profiles (common/inflow.glsl, HEMO_OPEN_BINS; hemo/sim/inflow.hpp):
// after the integrator, an invocation per bin (HEMO_OPEN_PROFILE_SIZE: every end's speed bins,
// then the planes' pressures). A bin's mean is its fixed-point sum over its count; a bin no
// particle sat in this step keeps the value it had (the pressures start at
// HEMO_OPEN_NO_PRESSURE: none yet). The sums go back to zero for the next step.
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "common/index.glsl"
#include "common/inflow.glsl"

layout(std430, binding = HEMO_OPROFILE_BINDING_SUMS) buffer Sums { uint sums[]; };
layout(std430, binding = HEMO_OPROFILE_BINDING_PROFILE) buffer Profile { float profile[]; };

void main() {
  const uint b = hemo_global_index();
  if (b >= HEMO_OPEN_PROFILE_SIZE) {
    return;
  }
  const bool pressure = b >= HEMO_OPEN_PRESSURE(0u);  // (the planes' mean pressures, Pa)
  const float scale = pressure ? HEMO_OPEN_PRESSURE_SCALE : HEMO_OPEN_FIXED_SCALE;
  const float offset = pressure ? HEMO_OPEN_PRESSURE_OFFSET : HEMO_OPEN_SPEED_OFFSET;
  const uint word = b * HEMO_OPEN_SUM_WORDS;
  const uint count = sums[word + 2u];
  if (count > 0u) {
    const float total = float(sums[word + 1u]) * 4294967296.0 + float(sums[word]);
    profile[b] = total / (float(count) * scale) - offset;
  }
  sums[word] = 0u;
  sums[word + 1u] = 0u;
  sums[word + 2u] = 0u;
}
