#version 450
// One invocation: the runs of the grid (HEMO_MC_RUN voxels along x per classify invocation)
// and the classify/compact dispatch over them. A grid with more runs than the buffers hold
// (only possible from a bad upload, which the host rejects first) extracts nothing.
#extension GL_GOOGLE_include_directive : require
#include "interface/mc.h"
#include "common/index.glsl"
#include "common/mc.glsl"

layout(std430, binding = HEMO_MC_PREPARE_BINDING_GRID) buffer Grid { McGrid grid; };
layout(std430, binding = HEMO_MC_PREPARE_BINDING_ARGS) buffer Args { uint args[16]; };
layout(push_constant) uniform Push {
  uint classifyWorkgroup;
  uint maxRuns;
} pc;

void main() {
  if (hemo_global_index() != 0u) {
    return;
  }
  const uvec3 points = grid.points.xyz;
  uint runs = 0u;
  uvec3 voxels = uvec3(0u);
  if (all(greaterThanEqual(points, uvec3(2u)))) {
    voxels = points - 1u;
    runs = ((voxels.x + HEMO_MC_RUN - 1u) / HEMO_MC_RUN) * voxels.y * voxels.z;
  }
  if (runs > pc.maxRuns) {
    runs = 0u;
  }
  grid.runs = uvec4((voxels.x + HEMO_MC_RUN - 1u) / HEMO_MC_RUN, voxels.y, voxels.z, runs);
  const uvec3 groups = hemo_mc_groups(runs, pc.classifyWorkgroup);
  args[HEMO_MC_ARGS_CLASSIFY + 0] = groups.x;
  args[HEMO_MC_ARGS_CLASSIFY + 1] = groups.y;
  args[HEMO_MC_ARGS_CLASSIFY + 2] = groups.z;
  args[HEMO_MC_ARGS_RUNS] = runs;
}
