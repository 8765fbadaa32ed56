#version 450
// The cluster pair passes' walk order (interface/sph.h, HEMO_CLUSTER_ORDER_WINDOW): one
// invocation per fluid cluster, after the build. Cluster c's rank in its window is the number
// of the window's clusters that sort before it by (front texels, back texels, cluster number);
// it writes itself to order[window start + rank]. The keys are distinct (the cluster number
// breaks ties), so the ranks are a permutation of the window and every slot is written once.
// The window's counts are read by every invocation of it, through texel fetches: on llvmpipe
// that is a gather at a uniform index, which costs about what any gather does, and the pass
// runs once per build (about 64 fetches per cluster).
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "common/index.glsl"

layout(binding = HEMO_CORDER_BINDING_CCOUNT) uniform usamplerBuffer clusterCount;
layout(std430, binding = HEMO_CORDER_BINDING_ORDER) writeonly buffer Order { uint order[]; };
layout(push_constant) uniform Push {
  uint clusters;  // the fluid's clusters: [0, clusters)
} pc;

// A cluster's sort key: its sections' texels (front in the high half), as the passes walk them.
uint hemo_order_key(uint counts) {
  const uint front = ((counts & 0xffffu) + 3u) >> 2u;
  const uint back = ((counts >> 16u) + 3u) >> 2u;
  return front << 16u | back;
}

void main() {
  const uint c = hemo_global_index();
  if (c >= pc.clusters) {
    return;
  }
  const uint start = c - c % HEMO_CLUSTER_ORDER_WINDOW;
  const uint end = min(start + HEMO_CLUSTER_ORDER_WINDOW, pc.clusters);
  const uint key = hemo_order_key(texelFetch(clusterCount, int(c)).x);
  uint rank = 0u;
  for (uint k = start; k < end; ++k) {
    const uint other = hemo_order_key(texelFetch(clusterCount, int(k)).x);
    rank += other < key || (other == key && k < c) ? 1u : 0u;
  }
  order[start + rank] = c;
}
