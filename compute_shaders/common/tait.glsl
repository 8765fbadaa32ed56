// Tait equation of state with a background pressure p_bg (Pa), ramped linearly from 0 at
// t = 0 over params.backgroundRamp seconds:
//   p = B ((rho / rho0)^7 - 1) + p_bg,  optionally clamped at 0.
// Needs SphParams.
float hemo_background_pressure(float time, SphParams params) {
  const float ramp = params.backgroundRamp > 0.0 ? clamp(time / params.backgroundRamp, 0.0, 1.0) : 1.0;
  return params.backgroundPressure * ramp;
}

float hemo_tait_pressure(float rho, float background, SphParams params) {
  const float ratio = rho / params.rho0;
  const float r2 = ratio * ratio;
  const float p = params.taitB * (r2 * r2 * r2 * ratio - 1.0) + background;
  return params.clampNegativePressure != 0u ? max(p, 0.0) : p;
}

// Under DFSPH (params.pressureSolver 1) the solve takes compression out, and the equation of
// state acts on expansion only: p = max(B ((min(rho, rho0) / rho0)^7 - 1) + p_bg, 0), p_bg at
// rho0 and above, falling to 0 as the blood expands, never below (the solve has no tension
// either). The lumen pressure therefore falls where the blood expands, as under WCSPH.
float hemo_expansion_pressure(float rho, float background, SphParams params) {
  const float ratio = min(rho, params.rho0) / params.rho0;
  const float r2 = ratio * ratio;
  return max(params.taitB * (r2 * r2 * r2 * ratio - 1.0) + background, 0.0);
}

// The pressure the density pass gives: the Tait law under WCSPH, its expansion side under DFSPH.
float hemo_state_pressure(float rho, float background, SphParams params) {
  const float tait = hemo_tait_pressure(rho, background, params);
  const float expansion = hemo_expansion_pressure(rho, background, params);
  return params.pressureSolver != 0u ? expansion : tait;
}

// The density the equation of state gives for pressure p (the inverse, for boundary
// particles).
float hemo_tait_density(float p, float background, SphParams params) {
  return params.rho0 * pow(max((p - background) / params.taitB + 1.0, 1.0e-6), 1.0 / 7.0);
}
