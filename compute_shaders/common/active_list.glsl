// Appending to an active list (the boundary-pressure passes' sort mode): the including shader
// declares `activeArgs` (uvec4: x the indirect dispatch's workgroups, w the entries so far) and
// the list itself. Needs GL_KHR_shader_subgroup_basic and _arithmetic.
//
// Returns the entry of an invocation that appends (`take`), and ~0u for the others; every
// invocation still running must call it. A SIMD group takes its entries with one atomic (one
// per invocation kept both cores' caches trading the count's line), so the list's order
// follows the scheduling, as before; each entry's result does not depend on its place. The
// invocation whose entry opens a workgroup's worth adds that workgroup to the dispatch.
uint hemo_active_append(bool take) {
  const uint one = take ? 1u : 0u;
  const uint rank = subgroupExclusiveAdd(one);
  const uint total = subgroupAdd(one);
  uint base = 0u;
  if (subgroupElect() && total > 0u) {
    base = atomicAdd(activeArgs.w, total);
  }
  base = subgroupMax(base);  // the elected invocation's (the others hold 0)
  const uint k = base + rank;
  if (take && k % gl_WorkGroupSize.x == 0u) {
    atomicAdd(activeArgs.x, 1u);
  }
  return take ? k : ~0u;
}
