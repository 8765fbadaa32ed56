// Exclusive scan across one workgroup, for passes that scan blocks of HEMO_SCAN_ITEMS
// elements per invocation (scan/scan_block.comp, grid/cell_scan.comp). Each invocation
// passes the total of its own items and gets back the sum of the totals of the invocations
// before it; *blockTotal is the sum over the whole workgroup. Subgroup inclusive scans combine
// invocations and subgroup totals are combined through shared memory; nothing assumes a
// subgroup size. Call in uniform control flow (it has barriers).
// Needs GL_KHR_shader_subgroup_basic and GL_KHR_shader_subgroup_arithmetic.

// At most one entry per subgroup; a subgroup has at least one invocation.
shared uint s_scanSubgroupOffset[gl_WorkGroupSize.x];
shared uint s_scanBlockTotal;

uint hemo_workgroup_exclusive_scan(uint total, out uint blockTotal) {
  const uint inclusive = subgroupInclusiveAdd(total);
  const uint subgroupTotal = subgroupAdd(total);
  if (subgroupElect()) {
    s_scanSubgroupOffset[gl_SubgroupID] = subgroupTotal;
  }
  barrier();
  // Subgroup 0 turns the subgroup totals into exclusive offsets, gl_SubgroupSize at a time.
  if (gl_SubgroupID == 0u) {
    uint carry = 0u;
    for (uint first = 0u; first < gl_NumSubgroups; first += gl_SubgroupSize) {
      const uint idx = first + gl_SubgroupInvocationID;
      const uint x = idx < gl_NumSubgroups ? s_scanSubgroupOffset[idx] : 0u;
      const uint incl = subgroupInclusiveAdd(x);
      if (idx < gl_NumSubgroups) {
        s_scanSubgroupOffset[idx] = carry + incl - x;
      }
      carry += subgroupAdd(x);
    }
    if (subgroupElect()) {
      s_scanBlockTotal = carry;
    }
  }
  barrier();
  blockTotal = s_scanBlockTotal;
  return s_scanSubgroupOffset[gl_SubgroupID] + inclusive - total;
}
