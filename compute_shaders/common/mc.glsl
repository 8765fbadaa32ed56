// Surface grid maths shared by the marching-cubes stages (layouts in interface/mc.h).
// The grid's description, written by mc/bounds.comp or mc/prepare.comp (storage) and read by
// the other passes as a uniform buffer (std140 and std430 agree: four 16-byte vectors; see
// common/sph_params.glsl for why uniform).
struct McGrid {
  vec4 origin;  // xyz: point (0,0,0) (m); w: voxel size (m)
  uvec4 points; // xyz: points per axis; w: row stride (ints per x-row, a multiple of 4)
  uvec4 runs;   // x: runs per x-row; y, z: voxels along y and z; w: run count
  vec4 level;   // x: iso level; y: splat planes per particle
};

uint hemo_mc_point(uvec3 p, McGrid g) {
  return p.x + g.points.w * (p.y + g.points.y * p.z);
}

// Workgroup counts covering `items` invocations: (x, y, 1), folded into y past the device's
// limit (common/index.glsl); shaders index with hemo_group_index() and skip the tail.
uvec3 hemo_mc_groups(uint items, uint workgroup) {
  return uvec3(hemo_fold_groups((items + workgroup - 1u) / workgroup), 1u);
}

// Corner c of a voxel: offset (c & 1, (c >> 1) & 1, (c >> 2) & 1).
uvec3 hemo_mc_corner(uint c) {
  return uvec3(c & 1u, (c >> 1u) & 1u, (c >> 2u) & 1u);
}

// Row stride for x-rows of `points` values: padded to whole ivec4s, so classify reads a run's
// corners with aligned vector loads.
uint hemo_mc_row_stride(uint points) {
  return (points + 3u) & ~3u;
}
