// The time step's reduction folded into the passes that write the per-particle limits (the
// fluid's force pass, then the wall stage when the scene has one): each workgroup reduces its
// limits to a (min, max) partial at index groupBase + its own, and counts itself finished;
// the workgroup that finishes last of all `groups` (both passes together) reduces every
// partial to the result and resets the count for the next use. The result does not depend on
// which workgroup is last (min and max are exact); any NaN makes it (NaN, NaN), so a blown-up
// step is never hidden. Folding the reduction into these passes saves llvmpipe a dispatch per
// force evaluation (docs/benchmarks.md, "Session 21").
// The including shader enables GL_KHR_shader_subgroup_basic, _arithmetic and _vote and
// declares
//   coherent buffer  { vec2 dtPartials[]; }
//   coherent buffer  { uint dtFinished; }
//   writeonly buffer { vec2 dtResult; }

shared vec2 s_dtSubgroup[gl_WorkGroupSize.x];
shared bool s_dtNan[gl_WorkGroupSize.x];
shared bool s_dtLast;

// The workgroup's (min, max) of every invocation's mm, NaN if any invocation saw one; valid
// in invocation 0. Called in uniform control flow (it has a barrier).
vec2 hemo_dt_workgroup_minmax(vec2 mm, bool nan) {
  const vec2 sub = vec2(subgroupMin(mm.x), subgroupMax(mm.y));
  const bool subNan = subgroupAny(nan);
  if (subgroupElect()) {
    s_dtSubgroup[gl_SubgroupID] = sub;
    s_dtNan[gl_SubgroupID] = subNan;
  }
  barrier();
  vec2 r = s_dtSubgroup[0];
  bool anyNan = s_dtNan[0];
  if (gl_LocalInvocationID.x == 0u) {
    for (uint s = 1u; s < gl_NumSubgroups; ++s) {
      r = vec2(min(r.x, s_dtSubgroup[s].x), max(r.y, s_dtSubgroup[s].y));
      anyNan = anyNan || s_dtNan[s];
    }
  }
  return anyNan ? vec2(uintBitsToFloat(0x7fc00000u)) : r;
}

// Every invocation of the workgroup calls this once, in uniform control flow, with its limit
// (s) and whether it has one.
void hemo_dt_fold(float limit, bool valid, uint groupBase, uint groups) {
  const float inf = uintBitsToFloat(0x7f800000u);
  const vec2 mm = valid ? vec2(limit) : vec2(inf, -inf);
  const vec2 partial = hemo_dt_workgroup_minmax(mm, valid && isnan(limit));
  if (gl_LocalInvocationID.x == 0u) {
    dtPartials[groupBase + hemo_group_index()] = partial;
    memoryBarrierBuffer();  // the partial is visible before the count says so
    s_dtLast = atomicAdd(dtFinished, 1u) == groups - 1u;
  }
  barrier();
  if (!s_dtLast) {
    return;  // the same for the whole workgroup
  }
  memoryBarrierBuffer();
  vec2 r = vec2(inf, -inf);
  bool nan = false;
  for (uint p = gl_LocalInvocationID.x; p < groups; p += gl_WorkGroupSize.x) {
    const vec2 v = dtPartials[p];
    nan = nan || any(isnan(v));
    r = vec2(min(r.x, v.x), max(r.y, v.y));
  }
  // (The first round's shared values were all read before the barrier after s_dtLast.)
  const vec2 total = hemo_dt_workgroup_minmax(r, nan);
  if (gl_LocalInvocationID.x == 0u) {
    dtResult = total;
    dtFinished = 0u;  // every other workgroup has counted itself: ready for the next use
  }
}
