// The inflow's time dependence (hemo/sim/inflow.hpp), for shaders that declare the
// InflowParams block (common/inflow.glsl) as `inflow` before including this.

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
  const float ramp = hemo_inflow_ramp(inflow, time);
  return inflow.meanSpeed * w * ramp;
}

// A pressure inlet's pressure over the background pressure at time t (Pa): its pressure_Pa
// times the waveform and the ramp (the loader gives a pressure inlet a mean speed of 1, so
// that is the mean speed's w(t) ramp(t)).
float hemo_inlet_pressure(float time) {
  return inflow.ends[0].drive.y * hemo_inflow_mean_speed(time);
}

// Open end e's pressure over the background pressure at time t (Pa; a pressure end's: the
// inlet's follows the waveform, an outlet's is constant).
float hemo_open_end_pressure(uint e, float time) {
  return e == 0u ? hemo_inlet_pressure(time) : inflow.ends[e].drive.y;
}
