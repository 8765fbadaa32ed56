// The step's dt from the time step's reduction (sph/dt_reduce.comp): the smallest limit, at
// most dtMax, and no further than the end time (0 once the clock has reached it). The
// integrator and the DFSPH solve (which must know the dt the step will take) share it.
// Needs common/clock.glsl.
float hemo_step_dt(ClockRecord clock, float endTime, float smallestLimit, float dtMax) {
  const float remaining = endTime - (clock.time - clock.compensation);
  return min(min(smallestLimit, dtMax), max(remaining, 0.0));
}
