// Specialization constants that every shader shares (common/index.glsl), set by
// gpu::ComputePipeline. Shared by GLSL and C++. A shader's own constants are 1, 2, ...
// (PipelineDesc::specialization).
#ifndef HEMO_INTERFACE_SPEC_H
#define HEMO_INTERFACE_SPEC_H

#define HEMO_SPEC_WORKGROUP_SIZE 0  // local_size_x
#define HEMO_SPEC_MAX_GROUPS_X 31   // min(maxComputeWorkGroupCount[0], [1], 65535)

#endif
