// The state a boundary or wall particle takes from its fluid neighbours' sums
// (sph/boundary_pressure.comp gives the model; sph/boundary_clusters.comp shares it):
//   sumW = sum_f W_bf, sumP = sum_f p_f W_bf, sumRhoR = sum_f rho_f (x_b - x_f) W_bf,
//   sumV = sum_f v_f W_bf,
// all zero for a particle without fluid within the support, which keeps (rho0, p_bg) and its
// own velocity. Under DFSPH (params.pressureSolver 1) every boundary particle takes (rho0, p_bg),
// as every fluid particle takes p_bg in the density pass: the solve holds the fluid off the
// wall through its own boundary term, and the background (lumen) pressure loads the wall
// through the force pass's pair terms. (A select after the
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
  const bool solved = params.pressureSolver != 0u;
  p = solved ? background : p;
  rho = solved ? params.rho0 : rho;
  state[b] = vec4(rho, p, 0.0, 0.0);
  const float volume = xb4.w / rho;  // 0 when detached
  pairPosition[b] = vec4(xb4.xyz, volume * p);
  viscousVel[b] = vec4(v, -volume);  // < 0: boundary or wall; -0 (neither) when detached
}
