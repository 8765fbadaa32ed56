#version 450
// Writes one row of step statistics (interface/stats.h) from the clock, the two maxima and
// the wall's counters. One invocation does the work.
#extension GL_GOOGLE_include_directive : require
#include "interface/stats.h"
#include "interface/wall.h"
#include "common/clock.glsl"

struct StatsRow {
  float time;
  float dt;
  float maxSpeed;
  float maxDensityError;
  uint broken;
  uint detached;
  uint steps;
  uint reserved;
};

layout(std430, binding = HEMO_STATSLOG_BINDING_CLOCK) readonly buffer Clock { ClockRecord clocks[2]; };
layout(std430, binding = HEMO_STATSLOG_BINDING_SPEED) readonly buffer Speed { vec2 speedMinMax; };
layout(std430, binding = HEMO_STATSLOG_BINDING_DENSITY_ERROR) readonly buffer DensityError { vec2 errorMinMax; };
layout(std430, binding = HEMO_STATSLOG_BINDING_WALL) readonly buffer Wall { uint wallCounters[4]; };
layout(std430, binding = HEMO_STATSLOG_BINDING_LOG) writeonly buffer Log { StatsRow rows[]; };
layout(push_constant) uniform Push { uint clockIn; uint row; } pc;

void main() {
  if (gl_GlobalInvocationID.x != 0u) {
    return;
  }
  const ClockRecord c = clocks[pc.clockIn];
  rows[pc.row] = StatsRow(c.time - c.compensation, c.lastDt, speedMinMax.y, errorMinMax.y,
                          wallCounters[HEMO_WALL_COUNTER_BROKEN], wallCounters[HEMO_WALL_COUNTER_DETACHED], c.steps, 0u);
}
