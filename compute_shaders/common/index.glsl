// Flat indices for 1D work that may be dispatched as a 2D grid of workgroups (when the
// group count exceeds maxComputeWorkGroupCount[0]); see gpu::ComputePipeline::groupsFor.
// The workgroup size comes from specialization constant 0 in every shader.
layout(local_size_x_id = 0) in;

uint hemo_group_index() {
  return gl_WorkGroupID.x + gl_WorkGroupID.y * gl_NumWorkGroups.x;
}

uint hemo_global_index() {
  return hemo_group_index() * gl_WorkGroupSize.x + gl_LocalInvocationID.x;
}

