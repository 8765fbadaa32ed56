// Neighbour walks without a list (hemo::sim::NeighbourSearch::Cells: the pair passes'
// variants compiled with HEMO_CELL_WALK = 1, interface/sph.h). A pass finds slot i's
// neighbours as the list build (sph/build_list.comp) would have: the candidate ranges around
// i's position at the last grid build (common/list_ranges.glsl), walked in the same order. A
// list entry is a candidate within the list radius at that build, and the rebuild test
// guarantees that every pair within the support now was one; so a pass that takes the
// candidates within its own range now meets, in the list's order, every pair of the list that
// adds anything, and its sums come out bit for bit the same (a pair that adds an exact zero
// changes no sum). What it costs is the candidates the list's radius test would have dropped,
// whose positions each pass loads.
// Compiled so, a pass binds, in place of its list's counts and entries (which the solver then
// does not allocate), the grid's positions at build as RGBA32UI texels and the grid's
// cellStart. The including shader defines before including this file
//   HEMO_WALK_BUILD_POSITIONS  its usamplerBuffer at the counts' slot
//   HEMO_WALK_CELL_START       its usamplerBuffer at the list's slot
// and has `params` bound.
#define cellStart HEMO_WALK_CELL_START
#include "common/grid.glsl"
#include "common/list_ranges.glsl"

#define hemo_params_grid() HemoGrid(params.gridOrigin, params.gridInvCell, params.gridDims, params.gridPeriodic)

// Slot j's position at the last build (m), its kind in w (grid/reorder.comp).
vec4 hemo_position_at_build(uint j) {
  return uintBitsToFloat(texelFetch(HEMO_WALK_BUILD_POSITIONS, int(j)));
}

// Slot i's candidate ranges into gRanges, as sph/build_list.comp finds them; returns how many.
uint hemo_walk_ranges(uint i) {
  const vec4 xb = hemo_position_at_build(i);
  const HemoGrid g = hemo_params_grid();
  bool outside;
  const ivec3 c = hemo_cell_coords(xb.xyz, g, outside);
  vec3 u = (xb.xyz - g.origin.xyz) * g.invCell.xyz;
  const vec3 dimsF = vec3(g.dimsN.xyz);
  u = mix(u, u - dimsF * floor(u / dimsF), notEqual(g.periodic.xyz, uvec3(0u)));
  return hemo_list_ranges(g, c, u, u, uint(xb.w) == HEMO_KIND_FLUID, params.listRadius);
}

// Whether slot i's list would hold any entry: a candidate other than i within the list radius
// at the last build (the boundary pass's sort: boundary slots list fluid neighbours only).
bool hemo_walk_lists_any(uint i) {
  const vec3 xb = hemo_position_at_build(i).xyz;
  const float list2 = params.listRadius * params.listRadius;
  const HemoPairParams pp = hemo_pair_params();
  const uint ranges = hemo_walk_ranges(i);
  for (uint r = 0u; r < ranges; ++r) {
    const uint end = gRanges[r].y & ~HEMO_LIST_BOUNDARY_BIT;
    for (uint j = gRanges[r].x; j < end; ++j) {
      const vec3 d = hemo_min_image(xb - hemo_position_at_build(j).xyz, pp);
      if (j != i && dot(d, d) < list2) {
        return true;
      }
    }
  }
  return false;
}
