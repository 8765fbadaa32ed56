#version 450
// Compact: after both scans, every active run writes its index at its place in the list of
// active runs (in run order). Invocation 0 turns the totals (entry `runs` of each scan) into
// the generate dispatch, the draw arguments and the counters, so the host never reads a count
// to go on. Triangles beyond the capacity are counted but not written.
#extension GL_GOOGLE_include_directive : require
#include "interface/mc.h"
#include "common/index.glsl"
#include "common/mc.glsl"

layout(std430, binding = HEMO_MC_COMPACT_BINDING_RUN_TRIANGLES) readonly buffer RunTriangles { uint runTriangles[]; };
layout(std430, binding = HEMO_MC_COMPACT_BINDING_RUN_ACTIVE) readonly buffer RunActive { uint runActive[]; };
layout(std430, binding = HEMO_MC_COMPACT_BINDING_ACTIVE_RUNS) writeonly buffer ActiveRuns { uint activeRuns[]; };
layout(std430, binding = HEMO_MC_COMPACT_BINDING_ARGS) buffer Args { uint args[16]; };
layout(push_constant) uniform Push {
  uint maxTriangles;
  uint generateWorkgroup;
} pc;

void main() {
  const uint r = hemo_global_index();
  const uint runs = args[HEMO_MC_ARGS_RUNS];
  if (r >= runs) {
    return;
  }
  const uint slot = runActive[r];
  if (runActive[r + 1u] != slot) {
    activeRuns[slot] = r;
  }
  if (r == 0u) {
    const uint triangles = runTriangles[runs];
    const uint activeCount = runActive[runs];
    const uint written = min(triangles, pc.maxTriangles);
    const uvec3 groups = hemo_mc_groups(activeCount * HEMO_MC_RUN, pc.generateWorkgroup);
    args[HEMO_MC_ARGS_GENERATE + 0] = groups.x;
    args[HEMO_MC_ARGS_GENERATE + 1] = groups.y;
    args[HEMO_MC_ARGS_GENERATE + 2] = groups.z;
    args[HEMO_MC_ARGS_DRAW + 0] = 3u * written;
    args[HEMO_MC_ARGS_DRAW + 1] = 1u;
    args[HEMO_MC_ARGS_DRAW + 2] = 0u;
    args[HEMO_MC_ARGS_DRAW + 3] = 0u;
    args[HEMO_MC_ARGS_TRIANGLES] = triangles;
    args[HEMO_MC_ARGS_ACTIVE_RUNS] = activeCount;
    args[HEMO_MC_ARGS_WRITTEN] = written;
  }
}
