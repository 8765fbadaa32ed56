// Tait equation of state p = B ((rho / rho0)^7 - 1), optionally clamped at 0. Needs SphParams.
float hemo_tait_pressure(float rho, SphParams params) {
  const float ratio = rho / params.rho0;
  const float r2 = ratio * ratio;
  const float p = params.taitB * (r2 * r2 * r2 * ratio - 1.0);
  return params.clampNegativePressure != 0u ? max(p, 0.0) : p;
}
