#version 450
// Time integration of fluid and wall particles (the stage is specialization constant 2):
//  symplectic Euler ... v += a dt, x += v dt
//  RK2 midpoint ....... stage 1 saves (x0, v0) and moves to x0 + v0 dt/2, v0 + a0 dt/2;
//                       stage 2 (after new forces at the midpoint) sets x = x0 + v dt,
//                       v = v0 + a dt. Only stage 2 advances the clock.
// dt = min(reduced
// per-particle limits, dtMax, endTime - t) read from the GPU (the host never sees dt inside a
// batch). Once the clock reaches endTime, steps change nothing (dt = 0, not counted).
// While t < dampingUntil the velocity is damped (a settling phase for validation scenes).
// Invocation 0 advances the clock (Kahan-compensated float sum) and logs (t, dt).
// A particle that becomes non-finite records the step in the status buffer.
// Every slot also writes its x displacement since the list was built and its reach for the
// neighbour-list check (sph/rebuild_check.comp reduces both).
// A fluid particle that starts the step in the inflow zone of a vessel moves along the axis at
// the prescribed velocity instead (hemo/sim/inflow.hpp), in every mode; across the section it
// moves freely.
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "common/index.glsl"
#include "common/sph_params.glsl"
#include "common/clock.glsl"
#include "common/inflow.glsl"

layout(std430, binding = HEMO_INTEGRATE_BINDING_POSITIONS) buffer Positions { vec4 positions[]; };
layout(std430, binding = HEMO_INTEGRATE_BINDING_VELOCITIES) buffer Velocities { vec4 velocities[]; };
// The same records as texels, for the reads (each invocation reads its own record before it
// writes it; interface/sph.h).
layout(binding = HEMO_INTEGRATE_BINDING_POSITIONS_IN) uniform samplerBuffer positionsIn;
layout(binding = HEMO_INTEGRATE_BINDING_VELOCITIES_IN) uniform samplerBuffer velocitiesIn;
// Read-only per-particle inputs are uniform texel buffers (interface/sph.h, "texel slots").
layout(binding = HEMO_INTEGRATE_BINDING_ACCEL) uniform samplerBuffer accelT;
#define accel(k) texelFetch(accelT, int(k))
HEMO_SPH_PARAMS_UNIFORM(HEMO_INTEGRATE_BINDING_PARAMS);
// Values every invocation reads at the same address are uniform buffers (common/sph_params.glsl
// says why).
layout(std140, binding = HEMO_INTEGRATE_BINDING_DT) uniform Dt { vec2 dtMinMax; };
// Two clock records: this step reads clocks[in] and invocation 0 writes clocks[1 - in], so no
// invocation can see a half-advanced clock (workgroups run in any order). (Read through a
// uniform binding of the same buffer, the step measured no faster.)
layout(std430, binding = HEMO_INTEGRATE_BINDING_CLOCK) buffer Clock { ClockRecord clocks[2]; };
layout(std430, binding = HEMO_INTEGRATE_BINDING_STATUS) buffer Status { uint status[]; };
layout(std430, binding = HEMO_INTEGRATE_BINDING_LOG) writeonly buffer Log { vec2 stepLog[]; };
layout(std430, binding = HEMO_INTEGRATE_BINDING_SAVED_POS) buffer SavedPos { vec4 savedPos[]; };
layout(std430, binding = HEMO_INTEGRATE_BINDING_SAVED_VEL) buffer SavedVel { vec4 savedVel[]; };
layout(std430, binding = HEMO_INTEGRATE_BINDING_STEP_DT) buffer StepDt { float stepDt; };
layout(binding = HEMO_INTEGRATE_BINDING_POS_AT_BUILD) uniform samplerBuffer posAtBuildT;
layout(std430, binding = HEMO_INTEGRATE_BINDING_DRIFT_X) writeonly buffer DriftX { float driftX[]; };
layout(std430, binding = HEMO_INTEGRATE_BINDING_REACH) writeonly buffer Reach { float reach[]; };
// The previous step's rebuild check (sph/rebuild_check.comp): (min d.x, max d.x, max reach,
// the middle of the range a step earlier).
layout(std140, binding = HEMO_INTEGRATE_BINDING_DRIFT_RANGE) uniform DriftRange { vec4 lastCheck; };
layout(std140, binding = HEMO_INTEGRATE_BINDING_INFLOW) uniform Inflow { InflowParams inflow; };
layout(binding = HEMO_INTEGRATE_BINDING_STATE) uniform samplerBuffer stateT;
#define state(k) texelFetch(stateT, int(k))
layout(std430, binding = HEMO_INTEGRATE_BINDING_NORMALS) buffer Normals { vec4 normals[]; };
// Continuity density (sph/density.comp): fluid particles carry their density in normals[i].w.
// 1 (symplectic Euler): the density pass advanced it (state.x); it is stored back for the next
// step. 2 (RK2 midpoint): the stages advance it with the rate in state.z, the first stage
// keeping rho(t) in savedVel.w. 0: summation density, nothing to carry.
layout(constant_id = 1) const uint kContinuity = 0u;
// The stage (HEMO_INTEGRATE_*): a constant, so each pipeline holds only its own stage's code.
// llvmpipe runs the body of a branch under a lane mask even when no lane takes it, and the
// stores of the RK2 stages cost the symplectic step about a third of this pass.
layout(constant_id = 2) const uint kMode = 0u;
layout(push_constant) uniform Push {
  uint n;
  uint step;
  uint logIndex;
  float endTime;
  uint clockIn;
} pc;

// A wall particle whose springs all broke is marked by the wall stage with accel.w < 0 (fluid
// particles keep a positive value there): from now on it has no SPH mass, so the fluid no
// longer sees it. (Written here, not by the wall stage, whose other invocations read the
// positions.)
float hemo_sph_mass(float mass, float accelW) {
  return accelW < 0.0 ? 0.0 : mass;
}

// Fluid and wall particles move (walls with the acceleration of wall/spring_forces.comp);
// rigid boundary particles do not.
bool hemo_moves(float kind) {
  return uint(kind) == HEMO_KIND_FLUID || uint(kind) == HEMO_KIND_WALL;
}

// The rebuild test's inputs (docs/architecture.md, "the rebuild test"): the x displacement
// d.x since the list build, and the reach
//   reach = |d - (c, 0, 0)|,  c = the middle (min d.x + max d.x) / 2 of this step, predicted
//                               linearly from those of the two steps before (2 m1 - m2),
// plus, when the next step evaluates forces at a midpoint (RK2), the farthest the next half
// step can take the particle, |v| min(dtMax, C_a h / (c0 + |v|)) / 2.
// Any vector c common to all slots keeps the test valid: two particles' separation has
// changed by |d_i - d_j| <= |d_i - c| + |d_j - c| <= 2 max reach, so the list holds every
// pair within the support while the largest reach stays under half the skin. Taking c in the
// middle of the flow's displacements halves the reach of a uniform or parabolic drift along x
// (a vessel's axis), which does not change who neighbours whom. Predicting the middle lets
// this pass compute the reach (no pass of its own, docs/benchmarks.md "Session 17"); the
// previous step's middle alone lagged the dam break's front by a step's motion, 15% of the
// threshold, and rebuilt the list 30 times in 600 steps against 21. After a rebuild both
// middles restart at 0 (sph/rebuild_check.comp).
void writeRebuildTest(uint i, vec3 x, vec3 v) {
  const vec3 d = hemo_min_image(x - texelFetch(posAtBuildT, int(i)).xyz, hemo_pair_params());
  driftX[i] = d.x;
  float c = (lastCheck.x + lastCheck.y) - lastCheck.w;  // 2 m1 - m2
  if (!(abs(c) < 1.0e30)) {
    c = 0.0;  // NaN (some particle was non-finite; its own reach is NaN and opens the gate)
  }
  float r = length(d - vec3(c, 0.0, 0.0));
  if (kMode == HEMO_INTEGRATE_RK2_FULL) {
    const float speed = length(v);
    r += 0.5 * speed * min(params.dtMax, params.cflAcoustic * params.h / (params.c0 + speed));
  }
  reach[i] = r;
}

// Mean inflow speed u(t) = U w(t) ramp(t) (m/s).
float hemo_inflow_mean_speed(float time) {
  float w = 1.0;
  if (inflow.period > 0.0 && inflow.samples > 0u) {
    const float cycles = time / inflow.period;
    const float phase = (cycles - floor(cycles)) * float(inflow.samples);
    const uint k = min(uint(phase), inflow.samples - 1u);
    const float a = hemo_inflow_sample(inflow, k);
    const float b = hemo_inflow_sample(inflow, (k + 1u) % inflow.samples);
    w = a + (b - a) * (phase - float(k));
  }
  const float ramp = inflow.ramp > 0.0 ? clamp(time / inflow.ramp, 0.0, 1.0) : 1.0;
  return inflow.meanSpeed * w * ramp;
}

// True when a fluid particle at x (start of the step) is in the inflow zone; u: its velocity,
// s2: its (r / R)^2.
bool hemo_inflow_driven(vec3 x, float kind, float time, out vec3 u, out float s2) {
  u = vec3(0.0);
  s2 = 0.0;
  if (inflow.enabled == 0u || uint(kind) != HEMO_KIND_FLUID || x.x < inflow.zoneStart || x.x >= inflow.zoneEnd) {
    return false;
  }
  const vec2 d = x.yz - vec2(inflow.centreY, inflow.centreZ);
  s2 = dot(d, d) / (inflow.radius * inflow.radius);
  if (s2 >= 1.0) {
    return false;  // outside the lumen (escaped blood is never driven)
  }
  const float profile = inflow.profile == 1u ? 1.0 : 2.0 * (1.0 - s2);
  u = vec3(hemo_inflow_mean_speed(time) * profile, 0.0, 0.0);
  return true;
}

void main() {
  const uint i = hemo_global_index();
  const ClockRecord clock = clocks[pc.clockIn];
  // The step's dt: from the reduction (Euler, RK2 first stage), or the one the first stage
  // stored (RK2 second stage, so both stages use the same dt).
  float dt;
  if (kMode == HEMO_INTEGRATE_RK2_FULL) {
    dt = stepDt;
  } else {
    const float remaining = pc.endTime - (clock.time - clock.compensation);
    dt = min(min(dtMinMax.x, params.dtMax), max(remaining, 0.0));
  }
  const bool running = dt > 0.0 || isnan(dt);  // false once the end time is reached
  if (kMode == HEMO_INTEGRATE_RK2_HALF) {
    if (i == 0u) {
      stepDt = dt;  // read by the second stage (a later dispatch)
    }
    if (running && i < pc.n && hemo_moves(texelFetch(velocitiesIn, int(i)).w)) {
      const vec4 v = texelFetch(velocitiesIn, int(i));
      const vec4 x = texelFetch(positionsIn, int(i));
      savedPos[i] = x;
      savedVel[i] = v;
      if (kContinuity == 2u && uint(v.w) == HEMO_KIND_FLUID) {
        const float rho = hemo_carried_density(normals[i].w, params.rho0);
        savedVel[i].w = rho;  // the second stage reads only savedVel.xyz as a velocity
        normals[i].w = rho + state(i).z * (0.5 * dt);
      }
      const vec4 a = accel(i);
      vec3 vMid = v.xyz + a.xyz * (0.5 * dt);
      vec3 drift = v.xyz;
      vec3 u;
      float s2;
      if (hemo_inflow_driven(x.xyz, v.w, clock.time - clock.compensation, u, s2)) {
        vMid.x = u.x;
        drift.x = u.x;
      }
      velocities[i] = vec4(vMid, v.w);
      positions[i] = vec4(hemo_wrap_position(x.xyz + drift * (0.5 * dt)), hemo_sph_mass(x.w, a.w));
    }
    return;
  }
  if (i == 0u) {
    ClockRecord next = clock;
    if (running) {
      const float y = dt - clock.compensation;
      next.time = clock.time + y;
      next.compensation = (next.time - clock.time) - y;
      next.lastDt = dt;
      next.steps = clock.steps + 1u;
    }
    clocks[1u - pc.clockIn] = next;
    stepLog[pc.logIndex] = vec2(next.time, running ? dt : 0.0);
  }
  if (i >= pc.n) {
    return;
  }
  vec4 v = texelFetch(velocitiesIn, int(i));
  vec4 x = texelFetch(positionsIn, int(i));
  if (!running || !hemo_moves(v.w)) {
    writeRebuildTest(i, x.xyz, v.xyz);
    return;
  }
  // Where the step started (the inflow zone is judged there).
  const vec3 start = kMode == HEMO_INTEGRATE_RK2_FULL ? savedPos[i].xyz : x.xyz;
  if (kMode == HEMO_INTEGRATE_RK2_FULL) {
    // midpoint rule: x1 = x0 + dt v(mid), v1 = v0 + dt a(mid)
    const vec4 v0 = savedVel[i];
    x.xyz = savedPos[i].xyz + v.xyz * dt;  // wrapped below: the saved position may be across the seam
    v.xyz = v0.xyz + accel(i).xyz * dt;
  } else {
    v.xyz += accel(i).xyz * dt;
  }
  if (clock.time < params.dampingUntil) {
    v.xyz /= 1.0 + params.dampingRate * dt;  // settling phase only (implicit, so never unstable)
  }
  vec3 u;
  float s2;
  if (hemo_inflow_driven(start, v.w, clock.time - clock.compensation, u, s2)) {
    // The axial velocity is prescribed; the motion across the section stays free, so
    // particles that enter the zone too close can still part (a fully kinematic zone froze
    // such pairs together: 6-13 kPa at its far end and an emptied slice after it).
    v.x = u.x;
    if (kMode == HEMO_INTEGRATE_RK2_FULL) {
      x.x = start.x + u.x * dt;  // across the section: the midpoint rule as everywhere
    } else {
      x.xyz += v.xyz * dt;
    }
    if (inflow.holdPressure != 0u) {
      // The lumen's supply: the mass moves a tenth of the way each step towards the one that
      // brings the density (of this step's last density pass) to rho0, between the initial
      // mass and the cap. Both ways, so the scatter of single densities does not ratchet the
      // mass up; a tenth, because every zone particle adjusts at once and the full step
      // overshoots on particle-scale patterns (measured: the zone ended 4% dense).
      // Only away from the wall (r < R - dp): next to it the summed density reads low (the
      // wall's two layers do not fill the kernel's support), and the outer ring took up to
      // 2.6 times its mass while the zone's middle ended 7% dense.
      const float inner = 1.0 - params.wallSpacing / inflow.radius;  // R - dp, over R
      const float rho = state(i).x;
      if (rho > 0.0 && s2 < inner * inner) {
        x.w = clamp(x.w * (1.0 + 0.1 * (inflow.restDensity / rho - 1.0)), inflow.baseMass, inflow.maxMass);
      }
    }
  } else if (kMode != HEMO_INTEGRATE_RK2_FULL) {
    x.xyz += v.xyz * dt;
  }
  x.xyz = hemo_wrap_position(x.xyz);
  if (any(isnan(x.xyz)) || any(isinf(x.xyz)) || any(isnan(v.xyz)) || any(isinf(v.xyz))) {
    atomicMin(status[HEMO_STATUS_FIRST_BAD_STEP], pc.step);
    atomicAdd(status[HEMO_STATUS_NONFINITE], 1u);
  }
  if (kContinuity != 0u && uint(v.w) == HEMO_KIND_FLUID) {
    // (non-finite densities show in the next force pass's blow-up diagnosis)
    normals[i].w = kContinuity == 1u ? state(i).x : savedVel[i].w + state(i).z * dt;
  }
  velocities[i] = v;
  x.w = hemo_sph_mass(x.w, accel(i).w);
  positions[i] = x;
  writeRebuildTest(i, x.xyz, v.xyz);
}
