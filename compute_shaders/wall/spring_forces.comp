#version 450
// Rupture and spring forces on wall particles, gathered per particle over its springs (CSR
// adjacency by particle id; no float atomics). A spring whose tension exceeds its maximum
// force breaks for good (the seed's rupture rule; its end a flags it). a = sum of the forces
// of the unbroken springs / mass + gravity, zero for anchored particles; and the particle's
// time-step limit min(N C sqrt(mass / sum of its unbroken stiffnesses), C_a h / (c0 + |v|))
// (the first bounds the phase error of its fastest oscillation in each of the N substeps the
// wall takes per step, wall/substep.comp; C is push.timeStepFactor; the second is the fluid's
// acoustic limit, which the neighbour-list look-ahead relies on). Other
// particle kinds are left alone. Its SIMD groups add their partials of the time step's
// reduction after the fluid force pass's (common/dt_fold.glsl).
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_vote : require
#include "interface/sph.h"
#include "interface/wall.h"
#include "common/index.glsl"
#include "wall/spring.glsl"
#include "common/kernel.glsl"
#include "common/sph_params.glsl"
#include "common/repulsion.glsl"

// Read-only inputs are uniform texel buffers (interface/sph.h, "texel slots").
layout(binding = HEMO_SPRINGF_BINDING_POSITIONS) uniform samplerBuffer positionsT;
layout(binding = HEMO_SPRINGF_BINDING_VELOCITIES) uniform samplerBuffer velocitiesT;
layout(binding = HEMO_SPRINGF_BINDING_IDS) uniform usamplerBuffer idsT;
layout(binding = HEMO_SPRINGF_BINDING_SLOT_OF_ID) uniform usamplerBuffer slotOfIdT;
layout(binding = HEMO_SPRINGF_BINDING_SPRINGS) uniform usamplerBuffer springsT;  // two uvec4 per Spring
layout(binding = HEMO_SPRINGF_BINDING_FIRST) uniform usamplerBuffer firstT;
layout(binding = HEMO_SPRINGF_BINDING_SPRINGS_OF) uniform usamplerBuffer springsOfT;
layout(binding = HEMO_SPRINGF_BINDING_WALL_INFO) uniform samplerBuffer wallInfoT;
layout(binding = HEMO_SPRINGF_BINDING_FLUID_ACCEL) uniform samplerBuffer fluidAccelT;  // read at fluid slots
layout(std430, binding = HEMO_SPRINGF_BINDING_ACCEL) writeonly buffer Accel { vec4 accel[]; };  // wall slots written
layout(std430, binding = HEMO_SPRINGF_BINDING_DT_LIMIT) writeonly buffer DtLimit { float dtLimit[]; };
HEMO_SPH_PARAMS_UNIFORM(HEMO_SPRINGF_BINDING_PARAMS);
layout(binding = HEMO_SPRINGF_BINDING_STATE) uniform samplerBuffer stateT;
layout(binding = HEMO_SPRINGF_BINDING_NCOUNT) uniform usamplerBuffer neighbourCountT;
layout(binding = HEMO_SPRINGF_BINDING_NLIST) uniform usamplerBuffer neighbourListT;
layout(std430, binding = HEMO_SPRINGF_BINDING_NORMALS) buffer Normals { vec4 normals[]; };  // own slot only
layout(std430, binding = HEMO_SPRINGF_BINDING_COUNTERS) buffer Counters { uint counters[]; };
layout(binding = HEMO_SPRINGF_BINDING_FRAMES) uniform usamplerBuffer framesT;  // R32G32 texels
layout(binding = HEMO_SPRINGF_BINDING_WALL_VEL) uniform samplerBuffer viscousVelT;
layout(binding = HEMO_SPRINGF_BINDING_PAIR_POSITION) uniform samplerBuffer pairPositionT;
// The springs again, for the broken flags this pass sets (rupture).
layout(std430, binding = HEMO_SPRINGF_BINDING_SPRINGS_RW) buffer SpringsRW { Spring springsRW[]; };
// The time step's reduction's first level (common/dt_fold.glsl).
layout(std430, binding = HEMO_SPRINGF_BINDING_DT_PARTIALS) writeonly buffer DtPartials { vec2 dtPartials[]; };
layout(std430, binding = HEMO_SPRINGF_BINDING_DT_COUNTS) writeonly buffer DtCounts { uint dtCounts[2]; };
// What the fluid and gravity give each wall slot for the step, (F_fluid / m + g, 0): read by
// wall/substep.comp (and added to by wall/dfsph_reaction.comp).
layout(std430, binding = HEMO_SPRINGF_BINDING_HELD) writeonly buffer Held { vec4 held[]; };
// The wall shear stress at wall slots, when push.wallShear is set (see hemo_fluid_reaction).
layout(std430, binding = HEMO_SPRINGF_BINDING_WSS) writeonly buffer Wss { vec4 wss[]; };
layout(binding = HEMO_SPRINGF_BINDING_VISCOSITY) uniform samplerBuffer viscosityT;  // at fluid slots

#define positions(k) texelFetch(positionsT, int(k))
#define velocities(k) texelFetch(velocitiesT, int(k))
#define slotOfId(k) texelFetch(slotOfIdT, int(k)).x
#define state(k) texelFetch(stateT, int(k))
#define viscousVel(k) texelFetch(viscousVelT, int(k))
#define pairPosition(k) texelFetch(pairPositionT, int(k))

// 4: the fluid's list is read four entries per texel (common/sph_params.glsl, hemo_list_texel)
layout(constant_id = 1) const uint kListWidth = 1u;
// 1: non-Newtonian blood: the fluid neighbour's own viscosity, 2 mu_f, where Newtonian blood
// has 2 params.mu (interface/sph.h, "Viscosity"; as sph/forces.comp's boundary pairs).
layout(constant_id = 2) const uint kViscosity = 0u;
#if HEMO_CELL_WALK
#define HEMO_WALK_BUILD_POSITIONS neighbourCountT
#define HEMO_WALK_CELL_START neighbourListT
#include "common/cell_walk.glsl"
#endif

layout(push_constant) uniform Push {
  vec4 gravity;
  uint n;
  uint idCount;
  float timeStepFactor;
  float acousticLength;  // C_a h (m): the fluid's acoustic limit C_a h / (c0 + |v|) applies too
  float c0;
  uint first;  // the slots [first, n): the fluid's, first after a sort, are left out
  uint dtPartialBase;  // this pass's first partial of the time step's reduction (past the force pass's)
  uint groupBase;      // the workgroups of the pass's earlier dispatches (the pages of the fluid's list)
  uint last;           // 1: the pass's last dispatch (it writes the partials' count)
  uint substeps;       // the wall's substeps per step (wall/substep.comp; 1: none)
  uint wallShear;      // 1: also the wall shear stress (HEMO_SPRINGF_BINDING_WSS)
} pc;

#include "wall/spring_gather.glsl"

// The force (N) the fluid exerts on wall particle w: minus the sum, over its fluid neighbours
// f, of m_f times the pair terms sph/forces.comp gave f for w (same formulas, same inputs),
// the repulsion with f's normalisation 1 / max(sum T, 1) from accel[f].w. With V = m / rho,
// m_f (V_w / rho_f) = V_w V_f, so the pressure and viscous terms come from f's pair data
// alone (two vec4, as in the force pass): m_f a = V_w [ -(V_f p_f + V_f p_w) gradW
// + 2 mu V_f (x . gradW) / (r^2 + eta^2) (v_f - v_w) ] (2 mu_f with non-Newtonian blood).
// The reaction loop's state, shared by its body (reactionPair()) whichever way the list is read.
HemoPairParams gPp;
HemoRepulsionParams gRp;
float gInvH, gGradNorm, gTwoMu, gEtaSq, gPW;
vec3 gXw, gVw, gNrm;
bool gRepels;
vec3 gSum;        // sum of V_f [ ... ] above, times V_w at the end
vec3 gRepulsion;  // sum of m_f a_repulsion
// Wall shear (with push.wallShear): the viscous part of gSum alone, and the fluid neighbours.
bool gShear;
vec3 gVisc;
uint gWet;

// One fluid neighbour f of the wall particle; `valid` is false for the padding of the list's
// last texel, which nobody wrote: the caller then passes the wall particle's own slot, so
// every fetch stays within the buffers, and the pair is dropped here.
void reactionPair(uint f, bool valid) {
  const vec4 pf = pairPosition(f);  // (x_f, V_f p_f)
  const vec3 d = hemo_min_image(pf.xyz - gXw, gPp);  // from w to f, as f sees it
  const float r2 = dot(d, d);
  if (!valid || r2 >= gPp.support2 || r2 == 0.0) {
    return;
  }
  const vec3 gradW = d * hemo_kernel_grad_factor(sqrt(r2), gInvH, gGradNorm);  // as sph/forces.comp
  const vec4 vf = viscousVel(f);  // (v_f, V_f)
  const float twoMu = kViscosity != 0u ? 2.0 * texelFetch(viscosityT, int(f)).x : gTwoMu;
  const vec3 viscous = (vf.w * twoMu * dot(d, gradW) / (r2 + gEtaSq)) * (vf.xyz - gVw);
  gSum += -(pf.w + vf.w * gPW) * gradW + viscous;
  if (gShear) {
    gVisc += viscous;
    gWet += 1u;
  }
  if (gRepels) {
    const float x = dot(d, gNrm);
    float weight;
    const float push = hemo_repulsion(x, length(d - x * gNrm), gRp, weight);
    if (weight > 0.0) {
      gRepulsion += gNrm * (positions(f).w * push * texelFetch(fluidAccelT, int(f)).w);
    }
  }
}

vec3 hemo_fluid_reaction(uint w) {
  gPp = hemo_pair_params();
  gInvH = 1.0 / gPp.h;
  gGradNorm = hemo_kernel_grad_norm(gPp.h, gPp.kernelNorm);
  gTwoMu = 2.0 * params.mu;
  gEtaSq = params.etaSq;
  gRp = hemo_repulsion_params(gPp.h, params.psi, params.repulsionCutoff, params.wallSpacing);
  const vec4 xw = positions(w);  // w: SPH mass
  const vec2 sw = state(w).xy;
  const float volumeW = xw.w / sw.x;
  gPW = sw.y;
  gXw = xw.xyz;
  gVw = viscousVel(w).xyz;
  gNrm = normals[w].xyz;
  gRepels = xw.w > 0.0;  // detached particles (no SPH mass) do not repel
  gSum = vec3(0.0);
  gRepulsion = vec3(0.0);
  gShear = pc.wallShear != 0u;
  gVisc = vec3(0.0);
  gWet = 0u;
#if HEMO_CELL_WALK
  const uint ranges = hemo_walk_ranges(w);  // the fluid's part only (common/cell_walk.glsl)
  for (uint r = 0u; r < ranges; ++r) {
    for (uint f = gRanges[r].x; f < gRanges[r].y; ++f) {
      reactionPair(f, true);
    }
  }
  const uint count = 0u;
#else
  const uint count = texelFetch(neighbourCountT, int(w)).x;
#endif
  for (uint k = 0u; k < count; k += 4u) {
    const uvec4 fs = hemo_list_quad(neighbourListT, w, k, count, gPp);
    reactionPair(fs.x, true);
    reactionPair(k + 1u < count ? fs.y : w, k + 1u < count);
    reactionPair(k + 2u < count ? fs.z : w, k + 2u < count);
    reactionPair(k + 3u < count ? fs.w : w, k + 3u < count);
  }
  if (gShear) {
    // The wall shear stress: the viscous force the fluid exerts on the particle (the viscous
    // part of its reaction, exactly what the fluid's viscous term took from it), less its
    // part along the normal, over the lumen area the particle carries (wallInfo.z: dp^2 over
    // the layers, each layer holding one point per dp^2 of the lumen). The layers share the
    // traction (the first takes most of it), so an average over a patch of wall points of all
    // layers is the wall shear stress there; it needs no fit to a velocity profile, which the
    // slip an SPH wall leaves at its surface would bias (by a quarter, in a Poiseuille tube of
    // radius 4 dp), and by momentum conservation its sum is the force the blood puts on the wall.
    const vec3 force = -volumeW * gVisc;
    const float area = texelFetch(wallInfoT, int(texelFetch(idsT, int(w)).x)).z;
    const vec3 tangential = force - dot(force, gNrm) * gNrm;
    wss[w] = vec4(area > 0.0 ? tangential / area : vec3(0.0), gWet > 0u ? 1.0 : 0.0);
  }
  const vec3 sum = gSum, repulsion = gRepulsion;
  return -(volumeW * sum + repulsion);
}

// The normal of the deformed wall from the particle's frame points, for the fluid's next force
// evaluation (this one, and the reaction, used the previous normal). Detached particles and
// particles without a frame keep theirs.
void updateNormal(uint slot, uint id) {
  const uvec2 frame = texelFetch(framesT, int(id)).xy;
  if (positions(slot).w == 0.0 || frame.x == HEMO_NO_FRAME) {
    return;
  }
  const vec3 x = positions(slot).xyz;
  const HemoPairParams pp = hemo_pair_params();
  const vec3 n = cross(hemo_min_image(positions(slotOfId(frame.x)).xyz - x, pp),
                       hemo_min_image(positions(slotOfId(frame.y)).xyz - x, pp));
  const float len = length(n);
  if (len > 0.0) {
    normals[slot] = vec4(n / len, 0.0);
  }
}


#include "common/dt_fold.glsl"

// The wall particle in `slot`: rupture of its springs, its acceleration and time-step limit
// (written, and returned). With substeps (pc.substeps > 1) it also keeps what the fluid and
// gravity give it for the whole step (held: wall/substep.comp adds the springs at each
// substep), and its limit on the step is substeps times the springs' own.
float hemo_wall(uint slot, uint id) {
  const vec4 info = texelFetch(wallInfoT, int(id));
  const bool anchored = info.y != 0.0;
  vec3 reaction = vec3(0.0);
  if (!anchored || pc.wallShear != 0u) {
    reaction = hemo_fluid_reaction(slot);  // (an anchored particle's is not used: it does not move)
  }
  float stiffness;
  uint intact, total;
  const vec3 springs = hemo_spring_gather(slot, id, stiffness, intact, total);
  if (anchored) {
    accel[slot] = vec4(0.0);
    held[slot] = vec4(0.0);
    dtLimit[slot] = 3.0e38;
    updateNormal(slot, id);
    return 3.0e38;
  }
  float marker = 0.0;
  if (intact == 0u && total > 0u && positions(slot).w != 0.0) {
    // All its springs are broken: the particle detaches from the wall for good. The integrator
    // sets its SPH mass to zero (marker accel.w < 0), so it no longer counts in the fluid's
    // density, pressure, viscosity or repulsion (the wall stops holding the fluid there); it
    // drifts on as debris.
    marker = -1.0;
    atomicAdd(counters[HEMO_WALL_COUNTER_DETACHED], 1u);
  } else {
    updateNormal(slot, id);
  }
  const vec3 outside = reaction / info.x + pc.gravity.xyz;
  accel[slot] = vec4((reaction + springs) / info.x + pc.gravity.xyz, marker);
  held[slot] = vec4(outside, 0.0);
  const float acoustic = pc.acousticLength / max(pc.c0 + length(velocities(slot).xyz), 1.0e-30);
  const float own = float(pc.substeps) * pc.timeStepFactor * sqrt(info.x / stiffness);
  const float limit = stiffness > 0.0 ? min(acoustic, own) : acoustic;
  dtLimit[slot] = limit;
  return limit;
}

void main() {
  const uint slot = pc.first + hemo_global_index();
  bool valid = false;
  float limit = 0.0;
  if (slot < pc.n && uint(velocities(slot).w) == HEMO_KIND_WALL) {
    const uint id = texelFetch(idsT, int(slot)).x;
    if (id < pc.idCount) {  // else not part of the spring network
      limit = hemo_wall(slot, id);
      valid = true;
    }
  }
  // every invocation: subgroup operations
  hemo_dt_partial(limit, valid, pc.dtPartialBase, 1u, pc.groupBase, pc.last != 0u);
}
