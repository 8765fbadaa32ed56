#version 450
// Boundary particles take the pressure the fluid next to them implies (Adami, Hu & Adams
// 2012, "A generalized wall boundary condition for SPH", eq. 27), for a rigid wall at rest:
//   p_b = ( sum_f p_f W_bf + g . sum_f rho_f (x_b - x_f) W_bf ) / sum_f W_bf
// with g the gravity + body force, and the density from the inverse Tait equation,
//   rho_b = rho0 ((p_b - p_bg) / B + 1)^(1/7)   (p_bg: background pressure, common/tait.glsl).
// For the viscous term the boundary particle shows the no-slip velocity of the same paper
// (eq. 22-23): v = 2 v_wall - sum_f v_f W_bf / sum_f W_bf, so the shear across the wall is
// that of a velocity that vanishes at the wall (a zero velocity gives about half of it, and
// the fluid slips).
// Also writes the particle's pair data (interface/sph.h): pair position (x, V p) and viscous
// velocity (no-slip v, -V), V = m / rho.
// A boundary particle without fluid neighbours keeps (rho0, p_bg) and its own velocity. The
// force pass then treats boundary particles like fluid ones in the symmetric pressure term,
// which holds a fluid column at the hydrostatic pressure without the wall having to be
// penetrated.
// Three modes (interface/sph.h): after each list build one pass over the non-fluid slots sets
// those without fluid neighbours in the list (no fluid particle reads them until the next
// build) and lists the others; each force evaluation then runs over that active list only.
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "common/index.glsl"
#include "common/kernel.glsl"
#include "common/sph_params.glsl"
#include "common/clock.glsl"
#include "common/tait.glsl"

// Read-only inputs: uniform texel buffers (interface/sph.h, "texel slots").
layout(binding = HEMO_BPRESSURE_BINDING_POSITIONS) uniform samplerBuffer positions;
layout(binding = HEMO_BPRESSURE_BINDING_VELOCITIES) uniform samplerBuffer velocities;
layout(binding = HEMO_BPRESSURE_BINDING_FLUID_STATE) uniform samplerBuffer fluidState;
HEMO_SPH_PARAMS_UNIFORM(HEMO_BPRESSURE_BINDING_PARAMS);
layout(std430, binding = HEMO_BPRESSURE_BINDING_STATE) writeonly buffer State { vec4 state[]; };
layout(binding = HEMO_BPRESSURE_BINDING_NCOUNT) uniform usamplerBuffer neighbourCount;
layout(binding = HEMO_BPRESSURE_BINDING_NLIST) uniform usamplerBuffer neighbourList;
layout(std430, binding = HEMO_BPRESSURE_BINDING_VISCOUS_VEL) writeonly buffer ViscousVel { vec4 viscousVel[]; };
layout(std140, binding = HEMO_BPRESSURE_BINDING_CLOCK) uniform Clock { ClockRecord clocks[2]; };
layout(std430, binding = HEMO_BPRESSURE_BINDING_PAIR_POSITION) writeonly buffer PairPosition { vec4 pairPosition[]; };
// 4: the list is read four entries per texel (common/sph_params.glsl, hemo_list_texel)
layout(constant_id = 1) const uint kListWidth = 1u;
#if HEMO_CELL_WALK
#define HEMO_WALK_BUILD_POSITIONS neighbourCount
#define HEMO_WALK_CELL_START neighbourList
#include "common/cell_walk.glsl"
#endif
layout(std430, binding = HEMO_BPRESSURE_BINDING_ACTIVE) buffer Active { uint activeSlots[]; };
layout(std430, binding = HEMO_BPRESSURE_BINDING_ACTIVE_ARGS) buffer ActiveArgs { uvec4 activeArgs; };
#include "common/boundary_state.glsl"
layout(push_constant) uniform Push {
  uint first;  // SORT and REST: the slots [first, n); after a sort the fluid's slots come
  uint n;      // first and are left out (SphSolver::nonFluidStart)
  uint clockIn;
  uint mode;   // HEMO_BPRESSURE_ACTIVE, _SORT or _REST
} pc;

// The loop's state, shared by its body (pair()) whichever way the list is read.
vec3 gXb;
HemoPairParams gPp;
float gInvH;
float gSumW, gSumP;
vec3 gSumRhoR, gSumV;

// One fluid neighbour f; `valid` is false for the padding of the list's last texel, which
// nobody wrote: the caller then passes the particle's own slot, so every fetch stays within
// the buffers (GPU-assisted validation checks that), and drops the pair here.
void pair(uint f, bool valid) {
  const vec3 d = hemo_min_image(gXb - texelFetch(positions, int(f)).xyz, gPp);
  const float r2 = dot(d, d);
  if (!valid || r2 >= gPp.support2) {
    return;
  }
  const float w = hemo_kernel_w_inv(sqrt(r2), gInvH, gPp.kernelNorm);
  const vec2 sf = texelFetch(fluidState, int(f)).xy;
  gSumW += w;
  gSumP += sf.y * w;
  gSumRhoR += sf.x * d * w;
  gSumV += texelFetch(velocities, int(f)).xyz * w;
}

void main() {
  uint b;
  if (pc.mode == HEMO_BPRESSURE_ACTIVE) {
    const uint k = hemo_global_index();
    if (k >= activeArgs.w) {
      return;
    }
    b = activeSlots[k];
  } else {
    b = pc.first + hemo_global_index();
    if (b >= pc.n) {
      return;
    }
  }
  const vec4 vb = texelFetch(velocities, int(b));
  if (uint(vb.w) == HEMO_KIND_FLUID) {
    return;
  }
  // fluid neighbours only (without a list: whether it would hold any, common/cell_walk.glsl)
#if HEMO_CELL_WALK
  const uint count = 0u;
  const bool listsFluid = pc.mode != HEMO_BPRESSURE_ACTIVE && hemo_walk_lists_any(b);
#else
  const uint count = texelFetch(neighbourCount, int(b)).x;
  const bool listsFluid = count > 0u;
#endif
  if (pc.mode != HEMO_BPRESSURE_ACTIVE && listsFluid) {
    if (pc.mode == HEMO_BPRESSURE_SORT) {
      // Appended in whatever order the invocations run; each entry's result does not depend
      // on its place. The invocation that opens a workgroup's worth of entries adds that
      // workgroup to the indirect dispatch.
      const uint k = atomicAdd(activeArgs.w, 1u);
      activeSlots[k] = b;
      if (k % gl_WorkGroupSize.x == 0u) {
        const uvec2 groups = hemo_fold_groups(k / gl_WorkGroupSize.x + 1u);  // (atomicMax: any order)
        atomicMax(activeArgs.x, groups.x);
        atomicMax(activeArgs.y, groups.y);
      }
    }
    return;
  }
  const vec4 xb4 = texelFetch(positions, int(b));
  const vec3 xb = xb4.xyz;
  gXb = xb;
  gPp = hemo_pair_params();
  gInvH = 1.0 / gPp.h;
  gSumW = 0.0;
  gSumP = 0.0;
  gSumRhoR = vec3(0.0);
  gSumV = vec3(0.0);
#if HEMO_CELL_WALK
  if (pc.mode == HEMO_BPRESSURE_ACTIVE) {
    const uint ranges = hemo_walk_ranges(b);  // the fluid's part only
    for (uint r = 0u; r < ranges; ++r) {
      for (uint f = gRanges[r].x; f < gRanges[r].y; ++f) {
        pair(f, true);
      }
    }
  }
#endif
  for (uint k = 0u; k < count; k += 4u) {
    const uvec4 fs = hemo_list_quad(neighbourList, b, k, count, gPp);
    pair(fs.x, true);
    pair(k + 1u < count ? fs.y : b, k + 1u < count);
    pair(k + 2u < count ? fs.z : b, k + 2u < count);
    pair(k + 3u < count ? fs.w : b, k + 3u < count);
  }
  const float background = hemo_background_pressure(clocks[pc.clockIn].time, params);
  hemo_boundary_store(b, xb4, vb.xyz, gSumW, gSumP, gSumRhoR, gSumV, background);
}
