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
