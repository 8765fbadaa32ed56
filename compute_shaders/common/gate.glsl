// Arming a dispatch gate (engine/gpu/gate.cpp) from inside another pass, by the invocations of
// the one workgroup that knows the decision: every slot's indirect arguments become the
// workgroup counts the host recorded (open) or zeros (closed), and an opening is counted. The including
// shader declares the gate's buffers as
//   readonly buffer  { uvec4 gateArmed[]; }   (DispatchGate::armedCounts)
//   writeonly buffer { uvec4 gateArgs[]; }    (DispatchGate::arguments)
//   buffer           { uint gateOpened; }     (DispatchGate::openings)
// gate/arm.comp does the same work as a pass of its own, one invocation per slot.

// Open when value > threshold or value is NaN (a blown-up value never skips the work that
// would report it).
bool hemo_gate_open(float value, float threshold) {
  return !(value <= threshold);
}

// Called by every invocation of the deciding workgroup with the same `open`: each writes its
// share of the slots (one thread walking 64-140 slots waited for each load in turn, 20-40 us
// on a GPU), and invocation 0 counts the opening.
void hemo_gate_arm(bool open, uint slots) {
  for (uint s = gl_LocalInvocationID.x; s < slots; s += gl_WorkGroupSize.x) {
    gateArgs[s] = open ? gateArmed[s] : uvec4(0u);
  }
  if (open && gl_LocalInvocationID.x == 0u) {
    gateOpened += 1u;
  }
}
