// Per-step statistics (compute_shaders/stats/). Shared by GLSL and C++.
#ifndef HEMO_INTERFACE_STATS_H
#define HEMO_INTERFACE_STATS_H

// stats/particle_stats.comp: per slot, the speed |v| (m/s) and the density error
// |rho / rho0 - 1| of fluid particles (0 for the others), for two max reductions.
#define HEMO_PSTATS_BINDING_VELOCITIES 0
#define HEMO_PSTATS_BINDING_STATE 1
#define HEMO_PSTATS_BINDING_PARAMS 2
#define HEMO_PSTATS_BINDING_SPEED 3
#define HEMO_PSTATS_BINDING_DENSITY_ERROR 4
#define HEMO_PSTATS_BINDING_COUNT 5

// stats/log_row.comp: one row of the step's statistics into the batch's log.
#define HEMO_STATSLOG_BINDING_CLOCK 0
#define HEMO_STATSLOG_BINDING_SPEED 1          // vec2 (min, max)
#define HEMO_STATSLOG_BINDING_DENSITY_ERROR 2  // vec2 (min, max)
#define HEMO_STATSLOG_BINDING_WALL 3           // uint[4] wall counters (zeros without a wall)
#define HEMO_STATSLOG_BINDING_LOG 4
#define HEMO_STATSLOG_BINDING_COUNT 5

// A row (std430, 32 bytes): float time (s, after the step), dt (s), max speed (m/s), max
// density error; uint broken springs, detached wall particles, steps (the clock's count), 0.

#endif
