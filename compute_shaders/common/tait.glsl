// Tait equation of state with a background pressure p_bg (Pa), ramped linearly from 0 at
// t = 0 over params.backgroundRamp seconds:
//   p = B ((rho / rho0)^7 - 1) + p_bg,  optionally clamped at 0.
// Needs SphParams.
float hemo_background_pressure(float time, SphParams params) {
  const float ramp = params.backgroundRamp > 0.0 ? clamp(time / params.backgroundRamp, 0.0, 1.0) : 1.0;
  return params.backgroundPressure * ramp;
}

// (Under DFSPH, params.pressureSolver 1, B = 0: p = p_bg, and the solve adds the rest.)
float hemo_tait_pressure(float rho, float background, SphParams params) {
  const float ratio = rho / params.rho0;
  const float r2 = ratio * ratio;
  const float p = params.taitB * (r2 * r2 * r2 * ratio - 1.0) + background;
  return params.clampNegativePressure != 0u ? max(p, 0.0) : p;
}

// The density the equation of state gives for pressure p (the inverse, for boundary
// particles).
float hemo_tait_density(float p, float background, SphParams params) {
  return params.rho0 * pow(max((p - background) / params.taitB + 1.0, 1.0e-6), 1.0 / 7.0);
}
