#version 450
// Marks the rebuild test's tiles (interface/sph.h, "the tile test") that hold rigid boundary
// particles: their displacement is always 0, and the integrator leaves their slots out, so the
// tile's box takes in the point 0 through this flag. Recorded once per particle upload (rigid
// particles never move), after the tile boxes were cleared.
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "common/index.glsl"
#include "common/tiles.glsl"

layout(binding = HEMO_TILE_STATIC_BINDING_POSITIONS) uniform samplerBuffer positions;
layout(binding = HEMO_TILE_STATIC_BINDING_VELOCITIES) uniform samplerBuffer velocities;
layout(std140, binding = HEMO_TILE_STATIC_BINDING_TILE_GRID) uniform TileGridBlock { TileGrid tiles; };
layout(std430, binding = HEMO_TILE_STATIC_BINDING_TILE_BOXES) buffer TileBoxes { uint tileBox[]; };
layout(push_constant) uniform Push {
  uint n;
} pc;

void main() {
  const uint i = hemo_global_index();
  if (i >= pc.n || uint(texelFetch(velocities, int(i)).w) != HEMO_KIND_BOUNDARY) {
    return;
  }
  const uint t = hemo_tile_index(hemo_tile_cell(texelFetch(positions, int(i)).xyz, tiles), tiles);
  atomicOr(tileBox[t * HEMO_TILE_WORDS + HEMO_TILE_STATIC_WORD], 1u);
}
