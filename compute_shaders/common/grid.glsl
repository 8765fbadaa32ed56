// Grid maths shared by the grid stages and the SPH list build.
// The grid's push constants (mirrored by hemo::sim::NeighbourGrid::Push):
//   origin.xyz   corner of cell (0,0,0) in m
//   invCell.xyz  cells per m along each axis
//   dimsN        xyz: cells per axis, w: particle count
//   periodic.xyz 1 on periodic axes: the grid then spans exactly one period there
//                (dims / invCell) and has at least 3 cells, so the 3 cells around any cell
//                are distinct; w: the grid's parts (interface/grid.h), 1 or 2.
struct HemoGrid {
  vec4 origin;
  vec4 invCell;
  uvec4 dimsN;
  uvec4 periodic;
};

// Cell coordinates of p, wrapped on periodic axes and clamped into the grid on the others.
// `outside` is set when clamping happened.
ivec3 hemo_cell_coords(vec3 p, HemoGrid g, out bool outside) {
  vec3 f = floor((p - g.origin.xyz) * g.invCell.xyz);
  const vec3 dims = vec3(g.dimsN.xyz);
  f = mix(f, f - dims * floor(f / dims), notEqual(g.periodic.xyz, uvec3(0u)));
  const vec3 hi = dims - 1.0;
  outside = any(lessThan(f, vec3(0.0))) || any(greaterThan(f, hi));
  // Clamp in float first so huge coordinates never overflow the int conversion.
  return ivec3(clamp(f, vec3(0.0), hi));
}

uint hemo_cell_linear(ivec3 c, uvec3 dims) {
  return uint(c.x) + dims.x * (uint(c.y) + dims.y * uint(c.z));
}

// Coordinate of the neighbour cell c + delta (|delta| < dim) along an axis of `dim` cells:
// wrapped on a periodic axis, -1 when it is off a bounded one.
int hemo_grid_step(int c, int delta, uint dim, uint periodic) {
  const int k = c + delta;
  if (periodic != 0u) {
    return k < 0 ? k + int(dim) : (k >= int(dim) ? k - int(dim) : k);
  }
  return (k < 0 || k >= int(dim)) ? -1 : k;
}

// The x-cells around cx as contiguous ranges [r.x, r.y]: one, or two where a periodic x
// axis wraps. Returns the number of ranges.
int hemo_x_ranges(int cx, HemoGrid g, out ivec2 r0, out ivec2 r1) {
  const int hi = int(g.dimsN.x) - 1;
  r1 = ivec2(0, -1);
  if (g.periodic.x != 0u && cx == 0) {
    r0 = ivec2(0, 1);
    r1 = ivec2(hi, hi);
    return 2;
  }
  if (g.periodic.x != 0u && cx == hi) {
    r0 = ivec2(0, 0);
    r1 = ivec2(hi - 1, hi);
    return 2;
  }
  r0 = ivec2(max(cx - 1, 0), min(cx + 1, hi));
  return 1;
}

// Minimum-image separation on periodic axes (unchanged on the others).
vec3 hemo_grid_min_image(vec3 d, HemoGrid g) {
  const vec3 period = vec3(g.dimsN.xyz) / g.invCell.xyz;
  return mix(d, d - period * round(d / period), notEqual(g.periodic.xyz, uvec3(0u)));
}

// The same for a loop over many d: the period (m, 0 on bounded axes) and its reciprocal (0
// on bounded axes) computed once, so each separation costs multiplications, not divisions.
struct HemoGridImage {
  vec3 period;
  vec3 invPeriod;
};

HemoGridImage hemo_grid_image(HemoGrid g) {
  const bvec3 periodic = notEqual(g.periodic.xyz, uvec3(0u));
  const vec3 period = vec3(g.dimsN.xyz) / g.invCell.xyz;
  return HemoGridImage(mix(vec3(0.0), period, periodic), mix(vec3(0.0), 1.0 / period, periodic));
}

vec3 hemo_grid_min_image(vec3 d, HemoGridImage image) {
  return d - image.period * round(d * image.invPeriod);
}
