// Dispatch gates (engine/gpu/gate.cpp): GPU-decided conditional work. Shared by GLSL and C++.
#ifndef HEMO_INTERFACE_GATE_H
#define HEMO_INTERFACE_GATE_H

// gate/arm.comp: one invocation per gated dispatch slot. Each slot is a uvec4 (x, y, z, 0)
// of workgroup counts; `args` is what the indirect dispatches read.
#define HEMO_GATE_BINDING_VALUES 0   // float[]: the decision value at push.index
#define HEMO_GATE_BINDING_ARMED 1    // uvec4[]: the counts recorded on the host
#define HEMO_GATE_BINDING_ARGS 2     // uvec4[]: the counts the dispatches use this time
#define HEMO_GATE_BINDING_OPENED 3   // uint: how many times the gate opened
#define HEMO_GATE_BINDING_COUNT 4

#endif
