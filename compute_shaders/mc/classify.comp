#version 450
// Classify: one invocation per run of up to HEMO_MC_RUN voxels along x. It reads the field at
// the run's corner points once (four x-rows, each an aligned ivec4 plus one value), forms
// each voxel's case (bit c set when corner c is inside: field > iso), and writes the run's triangle count, its active flag and its cases
// (8 bits each, x ascending). Both counts are then prefix-scanned; entries past the last run
// stay zero (the buffers are cleared before), so entry `runs` of a scan is the total.
#extension GL_GOOGLE_include_directive : require
#include "interface/mc.h"
#include "common/index.glsl"
#include "common/mc.glsl"

layout(std140, binding = HEMO_MC_CLASSIFY_BINDING_GRID) uniform Grid { McGrid grid; };
// Read-only inputs are uniform texel buffers (see interface/sph.h, "texel slots").
layout(binding = HEMO_MC_CLASSIFY_BINDING_FIELD) uniform isamplerBuffer field4;  // R32G32B32A32_SINT
// x of each entry: the case's triangle count. (A table of specialization constants in a
// local array was 2.7x slower on llvmpipe: dynamically indexed local arrays go through
// memory, one copy per invocation.)
layout(binding = HEMO_MC_CLASSIFY_BINDING_TABLE) uniform usamplerBuffer table;  // R32G32B32A32_UINT
layout(std430, binding = HEMO_MC_CLASSIFY_BINDING_RUN_TRIANGLES) writeonly buffer RunTriangles { uint runTriangles[]; };
layout(std430, binding = HEMO_MC_CLASSIFY_BINDING_RUN_ACTIVE) writeonly buffer RunActive { uint runActive[]; };
layout(std430, binding = HEMO_MC_CLASSIFY_BINDING_RUN_CASES) writeonly buffer RunCases { uint runCases[]; };
layout(std430, binding = HEMO_MC_CLASSIFY_BINDING_ARGS) readonly buffer Args { uint args[16]; };

void main() {
  const uint r = hemo_global_index();
  if (r >= args[HEMO_MC_ARGS_RUNS]) {
    return;
  }
  const McGrid g = grid;
  const uint rx = r % g.runs.x;
  const uint rest = r / g.runs.x;
  const uint vy = rest % g.runs.y;
  const uint vz = rest / g.runs.y;
  const uint x0 = rx * HEMO_MC_RUN;
  const uint count = min(uint(HEMO_MC_RUN), g.points.x - 1u - x0);
  // Fixed point: inside when value > iso * scale, compared exactly as floats of the integers.
  const float iso = g.level.x;
  // Bit k of row (dy + 2 dz): point x0 + k of that row is inside.
  uint rows[4];
  for (uint row = 0u; row < 4u; ++row) {
    const uint base = hemo_mc_point(uvec3(x0, vy + (row & 1u), vz + (row >> 1u)), g) / 4u;
    const ivec4 v = texelFetch(field4, int(base));
    // The fifth corner value lies in the row only when the run is full.
    const int last = count == 4u ? texelFetch(field4, int(base + 1u)).x : 0;
    const vec4 f = vec4(v) * (1.0 / HEMO_MC_FIXED_SCALE);
    const uint bits = (f.x > iso ? 1u : 0u) | (f.y > iso ? 2u : 0u) | (f.z > iso ? 4u : 0u) | (f.w > iso ? 8u : 0u) |
                      (float(last) * (1.0 / HEMO_MC_FIXED_SCALE) > iso ? 16u : 0u);
    rows[row] = bits & ((2u << count) - 1u);
  }
  // Corner c = x + 2y + 4z of voxel k is bit k + x of row y + 2z: two bits per row.
  uint triangles = 0u;
  uint cases = 0u;
  for (uint k = 0u; k < count; ++k) {
    const uint cube = ((rows[0] >> k) & 3u) | (((rows[1] >> k) & 3u) << 2u) | (((rows[2] >> k) & 3u) << 4u) |
                      (((rows[3] >> k) & 3u) << 6u);
    cases |= cube << (8u * k);
    triangles += texelFetch(table, int(cube)).x;
  }
  runTriangles[r] = triangles;
  runActive[r] = triangles > 0u ? 1u : 0u;
  runCases[r] = cases;
}
