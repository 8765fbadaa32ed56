// The rebuild test's tiles (interface/sph.h, "the tile test"): a regular grid over the domain,
// bound as a uniform buffer (std140), mirrored by hemo::sim::TileGrid in C++.
//   origin.xyz  the domain's lower corner (m); origin.w  half of (tile - support) (m): the
//               most the two largest reaches' half-sum may be for the tiles to decide
//   invSize.xyz 1 / the tile's size per axis (1/m); invSize.w  the skin squared (m^2)
//   count.xyz   tiles per axis; count.w  bit a set: axis a is periodic
// On a bounded axis particles beyond the domain fall into the edge tiles, which only widens
// them outward; on a periodic axis the tiles divide the period. Either way two tiles that are
// not neighbours (indices more than 1 apart, across the seam on a periodic axis) are a whole
// tile apart, at least 1.5 list radii.
struct TileGrid {
  vec4 origin;
  vec4 invSize;
  uvec4 count;
};

uvec3 hemo_tile_cell(vec3 x, TileGrid g) {
  // The same float operations as the C++ twin (TileGrid::cellOf): subtraction and product
  // are correctly rounded, so host and device agree on every particle's tile. A non-finite
  // position lands somewhere in range; its reach opens the gate anyway.
  const vec3 c = floor((x - g.origin.xyz) * g.invSize.xyz);
  return uvec3(clamp(ivec3(clamp(c, vec3(-1.0), vec3(g.count.xyz))), ivec3(0), ivec3(g.count.xyz) - 1));
}

uint hemo_tile_index(uvec3 c, TileGrid g) {
  return c.x + g.count.x * (c.y + g.count.y * c.z);
}

// An order key of a float: unsigned comparison of keys is the float comparison, and every
// finite value and +-inf has a nonzero key (0 stays "empty" in the tiles' maxima).
uint hemo_order_key(float f) {
  const uint u = floatBitsToUint(f);
  return (u & 0x80000000u) != 0u ? ~u : (u | 0x80000000u);
}

float hemo_order_value(uint k) {
  return uintBitsToFloat((k & 0x80000000u) != 0u ? (k & 0x7fffffffu) : ~k);
}
