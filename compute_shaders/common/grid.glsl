// Grid maths shared by the grid stages. Requires push constants with
// originInvCell (xyz: grid origin in m, w: 1 / cell size in 1/m) and dimsN (xyz: cells per axis).

// Cell coordinates of p, clamped into the grid. `outside` is set when clamping happened.
ivec3 hemo_cell_coords(vec3 p, vec4 originInvCell, uvec3 dims, out bool outside) {
  vec3 f = floor((p - originInvCell.xyz) * originInvCell.w);
  vec3 hi = vec3(dims) - 1.0;
  outside = any(lessThan(f, vec3(0.0))) || any(greaterThan(f, hi));
  // Clamp in float first so huge coordinates never overflow the int conversion.
  return ivec3(clamp(f, vec3(0.0), hi));
}

uint hemo_cell_linear(ivec3 c, uvec3 dims) {
  return uint(c.x) + dims.x * (uint(c.y) + dims.y * uint(c.z));
}
