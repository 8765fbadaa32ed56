// The time step's reduction, its first level folded into the passes that write the
// per-particle limits (the fluid's force pass, then the wall stage when the scene has one):
// each SIMD group reduces its limits to a (min, max) partial with subgroup operations and one
// lane stores it at partialBase + the group's index in the dispatch; invocation 0 stores how
// many partials the dispatch wrote in dtCounts[pass]. sph/dt_reduce.comp, one workgroup
// dispatched before the integrator, reduces the partials of both passes. The result does not
// depend on the order (min and max are exact); a NaN limit makes its partial (NaN, NaN), so a
// blown-up step is never hidden. (Reducing in each workgroup through shared memory, with the
// last to finish reducing the partials, cost the dam break's force pass 0.3-0.5 ms on
// lavapipe, more than a dispatch of its own: the barriers, the atomic counter and the tail
// llvmpipe runs under an empty mask in every workgroup.)
// The including shader enables GL_KHR_shader_subgroup_basic, _arithmetic and _vote and
// declares
//   writeonly buffer { vec2 dtPartials[]; }
//   writeonly buffer { uint dtCounts[2]; }  (3 in the tools' contact pass, which writes index 2)

// Every invocation of the dispatch calls one of these once, in uniform control flow. An
// invocation with several limits (the cluster passes) gives their (min, max) ((+inf, -inf)
// for none) and whether any is NaN.
// A pass dispatched in pieces (the pages of a split neighbour list, SphSolver) numbers its
// workgroups from `groupBase` on, so the pieces' partials follow one another, and only the
// last piece (`counts`) writes the count, which covers them all.
void hemo_dt_partial_range_of(vec2 mm, bool anyNan, uint partialBase, uint pass, uint groupBase, bool counts) {
  const vec2 sub = vec2(subgroupMin(mm.x), subgroupMax(mm.y));
  const bool nan = subgroupAny(anyNan);
  if (subgroupElect()) {
    dtPartials[partialBase + (groupBase + hemo_group_index()) * gl_NumSubgroups + gl_SubgroupID] =
        nan ? vec2(uintBitsToFloat(0x7fc00000u)) : sub;
  }
  if (counts && gl_LocalInvocationID.x == 0u && hemo_group_index() == 0u) {
    dtCounts[pass] = (groupBase + gl_NumWorkGroups.x * gl_NumWorkGroups.y * gl_NumWorkGroups.z) * gl_NumSubgroups;
  }
}

void hemo_dt_partial_range(vec2 mm, bool anyNan, uint partialBase, uint pass) {
  hemo_dt_partial_range_of(mm, anyNan, partialBase, pass, 0u, true);
}

// One limit (s), and whether the invocation has one; groupBase and counts as above.
void hemo_dt_partial(float limit, bool valid, uint partialBase, uint pass, uint groupBase, bool counts) {
  const float inf = uintBitsToFloat(0x7f800000u);
  hemo_dt_partial_range_of(valid ? vec2(limit) : vec2(inf, -inf), valid && isnan(limit), partialBase, pass, groupBase,
                           counts);
}
