// The interacting pairs of a fluid slot as the density pass kept them (interface/sph.h,
// HEMO_DENSITY_BINDING_PAIR_LIST), for the DFSPH passes (sph/dfsph_predict.comp,
// sph/dfsph_correct.comp): the including shader declares `pairCounts` and `pairList` (texel
// buffers, the list read kListWidth entries per texel), `gPp` (HemoPairParams) and
//   void pair(uint j, const bool boundary)
// which takes each pair in list order; the padding of a texel read passes j = i, a pair at
// zero distance whose gradient is exactly 0.
void hemo_dfsph_pair_range(uint i, uint first, uint end, const bool boundary) {
  // (one entry per texel: from `first` itself)
  for (uint k = kListWidth == 4u ? first & ~3u : first; k < end; k += 4u) {
    const uvec4 js = hemo_list_quad(pairList, i, k, end, gPp);
    pair(k >= first ? js.x : i, boundary);
    pair(k + 1u >= first && k + 1u < end ? js.y : i, boundary);
    pair(k + 2u >= first && k + 2u < end ? js.z : i, boundary);
    pair(k + 3u >= first && k + 3u < end ? js.w : i, boundary);
  }
}

// Every interacting pair of slot i: the fluid ones from the list's first entry, then the
// boundary ones, which end at its last.
void hemo_dfsph_pairs(uint i) {
  const uvec2 counts = hemo_pair_counts(texelFetch(pairCounts, int(i)).x);
  hemo_dfsph_pair_range(i, 0u, counts.x, false);
  hemo_dfsph_pair_range(i, params.neighbourCapacity - counts.y, params.neighbourCapacity, true);
}
