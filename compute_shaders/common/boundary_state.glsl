// The state a boundary or wall particle takes from its fluid neighbours' sums
// (sph/boundary_pressure.comp gives the model; sph/boundary_clusters.comp shares it):
//   sumW = sum_f W_bf, sumP = sum_f p_f W_bf, sumRhoR = sum_f rho_f (x_b - x_f) W_bf,
//   sumV = sum_f v_f W_bf,
// all zero for a particle without fluid within the support, which keeps (rho0, p_bg) and its
// own velocity. Under DFSPH (params.pressureSolver 1) a boundary particle takes rho0 and the
// weighted mean of its fluid neighbours' pressures, which the density pass gave from the
// expansion side of the equation of state (common/tait.glsl, hemo_expansion_pressure: p_bg
// unless the blood there has expanded): the solve holds the fluid off the wall through its own
// boundary term, and the lumen pressure loads the wall through the force pass's pair terms.
// (A select after the
// Tait model rather than a branch around it: with the branch, lavapipe's boundary pass took
// 13 times as long in Poiseuille flow.) Writes its state, pair position and viscous velocity
// (interface/sph.h). The
// including shader declares the params block and the buffers state, pairPosition and
// viscousVel.
void hemo_boundary_store(uint b, vec4 xb4, vec3 vb, float sumW, float sumP, vec3 sumRhoR, vec3 sumV,
                         float background) {
  float rho = params.rho0;
  float p = background;
  vec3 v = vb;
  if (sumW > 0.0) {
    v = 2.0 * vb - sumV / sumW;
    p = (sumP + dot(params.gravity.xyz, sumRhoR)) / sumW;
    if (params.clampNegativePressure != 0u) {
      p = max(p, 0.0);
    }
    rho = hemo_tait_density(p, background, params);
  }
  // (DFSPH: the fluid's own pressures, between 0 and p_bg, without the hydrostatic term, which
  // the solve's mirrored boundary term carries; the rest density)
  const bool solved = params.pressureSolver != 0u;
  p = solved ? (sumW > 0.0 ? clamp(sumP / sumW, 0.0, background) : background) : p;
  rho = solved ? params.rho0 : rho;
  state[b] = vec4(rho, p, 0.0, 0.0);
  const float volume = xb4.w / rho;  // 0 when detached
  pairPosition[b] = vec4(xb4.xyz, volume * p);
  viscousVel[b] = vec4(v, -volume);  // < 0: boundary or wall; -0 (neither) when detached
}
