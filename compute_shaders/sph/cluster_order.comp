#version 450
// The cluster pair passes' walk order (interface/sph.h, HEMO_CLUSTER_ORDER_WINDOW), one
// invocation per item after the build: list 0, the fluid's clusters [0, count); list 1, the
// boundary clusters' active list as appended (items[k], clusters counted from `base`; its
// length in activeArgs.w). An item's rank in its window is the number of the window's items
// that sort before it by (front texels, back texels, place); it writes its cluster to
// order[window start + rank]. The keys are distinct (the place breaks ties), so the ranks are
// a permutation of the window and every place is written once. Every invocation reads its
// window's counts through texel fetches: on llvmpipe a gather at a uniform index costs what
// any gather does, and the pass runs once per build (about 64 fetches per item).
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "common/index.glsl"

layout(binding = HEMO_CORDER_BINDING_CCOUNT) uniform usamplerBuffer clusterCount;
layout(std430, binding = HEMO_CORDER_BINDING_ORDER) writeonly buffer Order { uint order[]; };
layout(binding = HEMO_CORDER_BINDING_ITEMS) uniform usamplerBuffer items;
layout(std430, binding = HEMO_CORDER_BINDING_ACTIVE_ARGS) readonly buffer ActiveArgs { uvec4 activeArgs; };
layout(push_constant) uniform Push {
  uint count;  // list 0: the items; list 1: at most this many
  uint list;   // 0: the fluid's clusters; 1: the boundary clusters' active list
  uint base;   // list 1: the first boundary cluster
} pc;

// The cluster at place k.
uint hemo_order_item(uint k) {
  return pc.list == 0u ? k : texelFetch(items, int(k)).x;
}

// A cluster's sort key: its sections' texels (front in the high half), as the passes walk them.
uint hemo_order_key(uint cluster) {
  const uint counts = texelFetch(clusterCount, int(cluster + (pc.list == 0u ? 0u : pc.base))).x;
  const uint front = ((counts & 0xffffu) + 3u) >> 2u;
  const uint back = ((counts >> 16u) + 3u) >> 2u;
  return front << 16u | back;
}

void main() {
  const uint g = hemo_global_index();
  const uint count = pc.list == 0u ? pc.count : min(activeArgs.w, pc.count);
  if (g >= count) {
    return;
  }
  const uint start = g - g % HEMO_CLUSTER_ORDER_WINDOW;
  const uint end = min(start + HEMO_CLUSTER_ORDER_WINDOW, count);
  const uint item = hemo_order_item(g);
  const uint key = hemo_order_key(item);
  uint rank = 0u;
  for (uint k = start; k < end; ++k) {
    const uint other = hemo_order_key(hemo_order_item(k));
    rank += other < key || (other == key && k < g) ? 1u : 0u;
  }
  order[start + rank] = item;
}
