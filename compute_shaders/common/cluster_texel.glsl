// A texel of a cluster's list (interface/sph.h, "Clusters"): its entries k .. k + 3, of which
// those in [first, end) are live. The others are a section's padding: they get slot `own`, any
// slot whose data the pass may read (finite, and not written by the pass itself), and live 0,
// which the kernels' *_live forms (common/kernel.glsl) turn into a term of 0. Needs
// interface/sph.h.
ivec4 hemo_cluster_slots(uvec4 e, uint k, uint first, uint end, uint own, out vec4 live) {
  const uvec4 at = uvec4(k) + uvec4(0u, 1u, 2u, 3u);
  const bvec4 valid = bvec4(uvec4(greaterThanEqual(at, uvec4(first))) & uvec4(lessThan(at, uvec4(end))));
  live = vec4(valid);
  return ivec4(mix(uvec4(own), e & HEMO_CLUSTER_SLOT_MASK, valid));
}

// A walk over a cluster's list a texel at a time: its first `aTexels` texels hold the entries
// [0, a) (the front section, or none), the `texels - aTexels` after them those of [b, capacity)
// (the back section from its first texel, or none). `counts` is the cluster's packed count
// (front | back << 16).
struct HemoClusterWalk {
  uint texels;
  uint aTexels;
  uint a;
  uint b;
  uint capacity;
};

// The front section if `take`, else nothing.
HemoClusterWalk hemo_cluster_front(uint counts, bool take) {
  const uint a = counts & 0xffffu;
  const uint aTexels = take ? (a + 3u) >> 2u : 0u;
  return HemoClusterWalk(aTexels, aTexels, a, 0u, 0u);
}

// The front section unless `frontWalked`, then the back section.
HemoClusterWalk hemo_cluster_rest(uint counts, bool frontWalked, uint capacity) {
  const uint a = counts & 0xffffu;
  const uint back = counts >> 16u;
  const uint aTexels = frontWalked ? 0u : (a + 3u) >> 2u;
  return HemoClusterWalk(aTexels + ((back + 3u) >> 2u), aTexels, a, capacity - back, capacity);
}

// Texel t of the walk: its first entry k and the live entries' range [first, end).
void hemo_cluster_walk_texel(HemoClusterWalk w, uint t, out uint k, out uint first, out uint end) {
  const bool inA = t < w.aTexels;
  k = inA ? t << 2u : (w.b & ~3u) + ((t - w.aTexels) << 2u);
  first = inA ? 0u : w.b;
  end = inA ? w.a : w.capacity;
}
