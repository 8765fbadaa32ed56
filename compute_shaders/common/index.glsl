// Flat indices for 1D work that may be dispatched as a 2D grid of workgroups (when the
// group count exceeds maxComputeWorkGroupCount[0]); see gpu::ComputePipeline::groupsFor.
// The workgroup size comes from specialization constant 0 in every shader.
#include "interface/spec.h"
layout(local_size_x_id = HEMO_SPEC_WORKGROUP_SIZE) in;

// The most workgroups a dispatch may have along x (and along y): the device's
// maxComputeWorkGroupCount, capped at 65535, the least Vulkan allows. Set by the host
// (ComputePipeline, constant HEMO_SPEC_MAX_GROUPS_X) from the limits it reads, so a test can
// force it low and run the folded path on any device.
layout(constant_id = HEMO_SPEC_MAX_GROUPS_X) const uint kHemoMaxGroupsX = 65535u;

uint hemo_group_index() {
  return gl_WorkGroupID.x + gl_WorkGroupID.y * gl_NumWorkGroups.x;
}

uint hemo_global_index() {
  return hemo_group_index() * gl_WorkGroupSize.x + gl_LocalInvocationID.x;
}


// Workgroup counts (x, y) that cover `groups` workgroups, folded into y when x would pass
// kHemoMaxGroupsX, for indirect arguments a shader writes (as ComputePipeline::groupsFor folds
// the host's); the shaders they start index with hemo_group_index() and skip the tail.
uvec2 hemo_fold_groups(uint groups) {
  if (groups <= kHemoMaxGroupsX) {
    return uvec2(groups, 1u);
  }
  return uvec2(kHemoMaxGroupsX, (groups + kHemoMaxGroupsX - 1u) / kHemoMaxGroupsX);
}
