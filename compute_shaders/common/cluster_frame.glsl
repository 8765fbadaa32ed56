// A cluster's members in one frame across the periodic seams, so that the pair loops take the
// minimum image once per list entry instead of once per member and entry (docs/architecture.md,
// "Clusters"). Needs interface/sph.h and common/sph_params.glsl (kPeriodicAxes).
//
// The members are moved by whole periods to the images nearest member 0, and the cluster's
// centre c is the middle of their box. A neighbour j within the support 2h of a member m then
// has, along each periodic axis of period P, its minimum image y (the one nearest m) within
// s + 2h of c, s being half the box's extent along that axis; when s + 2h < P / 2, y is also
// the image nearest c. So a compact cluster (extent < P - 4h on every periodic axis) takes
// each entry's image nearest c once and the plain difference per member; the separations that
// matter are then the minimum images, and every other one is a longer separation, which the
// kernel also gives 0 (it is at least the minimum image's). A wider cluster (members in rows
// of cells far apart, in a sparse region; or a period near its least, 2.5 list radii) takes
// the minimum image per member and entry, as before. On bounded axes nothing moves: a scene
// without periodic axes gets exactly its positions and every cluster is compact.

// p moved by whole periods to the image nearest c (unchanged on bounded axes; written out
// rather than as c - hemo_min_image(c - p), which would round p on every axis).
vec3 hemo_image_near(vec3 p, vec3 c, HemoPairParams pp) {
  vec3 r = p;
  if ((kPeriodicAxes & 1u) != 0u) r.x = p.x + pp.period.x * round((c.x - p.x) * pp.invPeriod.x);
  if ((kPeriodicAxes & 2u) != 0u) r.y = p.y + pp.period.y * round((c.y - p.y) * pp.invPeriod.y);
  if ((kPeriodicAxes & 4u) != 0u) r.z = p.z + pp.period.z * round((c.z - p.z) * pp.invPeriod.z);
  return r;
}

// Moves x[1..] to the images nearest x[0] and returns whether the cluster is compact, with its
// centre in `centre`. The margin (1e-4 of the period) keeps float rounding away from the bound;
// a non-finite position makes the cluster wide (the exact loop then meets it, as before).
bool hemo_cluster_frame(inout vec3 x[HEMO_CLUSTER_SIZE], HemoPairParams pp, out vec3 centre) {
  vec3 lo = x[0], hi = x[0];
  for (uint m = 1u; m < HEMO_CLUSTER_SIZE; ++m) {
    x[m] = hemo_image_near(x[m], x[0], pp);
    lo = min(lo, x[m]);
    hi = max(hi, x[m]);
  }
  centre = 0.5 * (lo + hi);
  // (an axis of period 0 is bounded: nothing moves there, whatever kPeriodicAxes says)
  const bvec3 within = bvec3(uvec3(lessThan(hi - lo, 0.9999 * pp.period - 4.0 * pp.h)) |
                             uvec3(equal(pp.period, vec3(0.0))));
  bool compact = true;
  if ((kPeriodicAxes & 1u) != 0u) compact = compact && within.x;
  if ((kPeriodicAxes & 2u) != 0u) compact = compact && within.y;
  if ((kPeriodicAxes & 4u) != 0u) compact = compact && within.z;
  // min/max drop a NaN; a member's NaN makes the cluster wide
  for (uint m = 0u; m < HEMO_CLUSTER_SIZE; ++m) {
    compact = compact && !any(isnan(x[m])) && !any(isinf(x[m]));
  }
  return compact;
}
