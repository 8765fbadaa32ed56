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

// The flat index with the workgroups interleaved over the dispatch, for passes whose cost
// varies along the slots (the SPH grid puts the fluid's slots first, and a fluid particle
// costs far more than a boundary one). llvmpipe gives each of its threads one contiguous
// chunk of a dispatch's workgroups, so those chunks would not balance. Workgroup g runs
// block (g mod R) C + g / R, C = floor(G / R) for G workgroups: a bijection on [0, R C), so
// any chunk of consecutive g takes a share of each of the R stretches of the slot range. The
// last G - R C (< R) workgroups keep their own blocks. A GPU schedules workgroups dynamically
// and does not mind the order.
const uint kHemoInterleave = 16u;  // R

uint hemo_interleaved_index() {
  const uint groups = gl_NumWorkGroups.x * gl_NumWorkGroups.y;
  const uint g = hemo_group_index();
  const uint stretch = groups / kHemoInterleave;  // C
  const uint block = g < stretch * kHemoInterleave ? (g % kHemoInterleave) * stretch + g / kHemoInterleave : g;
  return block * gl_WorkGroupSize.x + gl_LocalInvocationID.x;
}
