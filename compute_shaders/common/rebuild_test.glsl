// Helpers of the neighbour list's rebuild test shared by the integrator, which computes each
// slot's reach, and sph/rebuild_decide.comp, which reduces the partials and decides
// (docs/architecture.md, "the rebuild test").

// The middle c of this step's x-displacement range, predicted linearly from the last result
// (min d.x, max d.x, half-sum, the middle a step before): 2 m1 - m2. A non-finite result
// (some particle was non-finite; its own reach is NaN and opens the gate) predicts 0.
float hemo_predicted_middle_of(vec4 last) {
  const float c = (last.x + last.y) - last.w;
  return abs(c) < 1.0e30 ? c : 0.0;
}

// The two largest of a1 >= a2 and b1 >= b2.
vec2 hemo_top2(vec2 a, vec2 b) {
  return vec2(max(a.x, b.x), max(min(a.x, b.x), max(a.y, b.y)));
}

// Two partials (min d.x, max d.x, the two largest reaches) combined.
vec4 hemo_rebuild_combine(vec4 a, vec4 b) {
  return vec4(min(a.x, b.x), max(a.y, b.y), hemo_top2(a.zw, b.zw));
}
