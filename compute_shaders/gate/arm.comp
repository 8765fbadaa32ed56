#version 450
// Opens or closes a dispatch gate: the gate is open when values[index] > threshold or is not
// a number (so a blown-up value never skips the work that would report it). Open: every
// slot's indirect arguments become the workgroup counts the host recorded; closed: zero
// workgroups, and the gated dispatches do nothing. One invocation per slot; a pass that
// computes the decision itself can arm the gate with common/gate.glsl's hemo_gate_arm.
#extension GL_GOOGLE_include_directive : require
#include "interface/gate.h"
#include "common/index.glsl"

layout(std430, binding = HEMO_GATE_BINDING_VALUES) readonly buffer Values { float values[]; };
layout(std430, binding = HEMO_GATE_BINDING_ARMED) readonly buffer Armed { uvec4 gateArmed[]; };
layout(std430, binding = HEMO_GATE_BINDING_ARGS) writeonly buffer Args { uvec4 gateArgs[]; };
layout(std430, binding = HEMO_GATE_BINDING_OPENED) buffer Opened { uint gateOpened; };
layout(push_constant) uniform Push { uint slots; uint index; float threshold; } pc;

#include "common/gate.glsl"

void main() {
  const uint slot = hemo_global_index();
  const bool open = hemo_gate_open(values[pc.index], pc.threshold);
  if (slot == 0u && open) {
    gateOpened += 1u;  // a single writer
  }
  if (slot < pc.slots) {
    gateArgs[slot] = open ? gateArmed[slot] : uvec4(0u);
  }
}
