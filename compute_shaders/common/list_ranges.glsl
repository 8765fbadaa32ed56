// The candidate ranges of a neighbour-list build (sph/build_list.comp for one particle,
// sph/build_clusters.comp for a row group of a cluster's members): the grid's cells are at
// least half the list radius R wide along y and z and narrower along x (sph.cpp, gridFor), so
// every neighbour of a box of points within one row of cells lies in the 5 x 5 rows (dz, dy in
// -2..2) around that row, each within reachX cells in x of the box's cells. A row is skipped
// when its nearest point is R or more away from the box in (y, z), and its x-cells are trimmed
// to those within the remaining reach sqrt(R^2 - gy^2 - gz^2). Cells are trimmed against a
// slightly larger radius, so rounding never drops a cell that holds a neighbour; the builds'
// distance tests are exact.
// The non-empty ranges of slots to scan go to gRanges in list order: [x, y) with y carrying
// HEMO_LIST_BOUNDARY_BIT for the boundary part. At most 5 x 5 rows, two ranges each where a
// periodic x axis wraps, in each of the two parts. Fluid points walk both parts (the
// boundary part only in planes whose rows hold some of it); boundary points walk only the
// fluid part, and skip planes without fluid. The including shader declares
//   uniform usamplerBuffer cellStart;   (interface/grid.h, two parts)
// and, to trim each row to the points themselves rather than their box, defines
// HEMO_LIST_POINTS (how many) and declares vec3 gListPoints[HEMO_LIST_POINTS] (in cell units,
// inside the box) and uint gListPointMask (the points of the box).

uvec2 gRanges[100];

// Distance in cell units from the interval [a, b] to cell k along one axis; on a bounded axis
// the first and last cells reach to infinity, as particles outside the grid are clamped into
// them.
float hemo_cell_gap(int k, float a, float b, uint dim, uint periodic) {
  float lo = float(k);
  float hi = float(k + 1);
  if (periodic == 0u) {
    lo = k <= 0 ? -3.0e38 : lo;
    hi = k >= int(dim) - 1 ? 3.0e38 : hi;
  }
  return max(0.0, max(lo - b, a - hi));
}

// The ranges around the box [lo, hi] (cell units, in the period of the row's cells on periodic
// axes) of points in the row of cell c (y and z; x from floor(lo.x) to floor(hi.x)), for list
// radius `radius` (m). Returns how many it wrote.
uint hemo_list_ranges(HemoGrid grid, ivec3 c, vec3 lo, vec3 hi, bool fluid, float radius) {
  const uvec3 dims = grid.dimsN.xyz;
  const uint cellCount = dims.x * dims.y * dims.z;
  const vec3 cellM = 1.0 / grid.invCell.xyz;  // cell size per axis, m
  const int hiX = int(dims.x) - 1;
  const int reachX = int(ceil(radius * grid.invCell.x));  // x-cells within R either way
  // On a bounded x axis a box outside the grid is taken at the edge cell it is clamped into,
  // in float before the int conversion: from its own far coordinate the trimmed range missed
  // the edge cell, so it did not list the particles there that listed it (the lists must be
  // symmetric: each pair's forces act on both).
  const bool boundedX = grid.periodic.x == 0u;
  const float cellsX = float(hiX);
  const int cxLo = int(boundedX ? clamp(floor(lo.x), 0.0, cellsX) : floor(lo.x));
  const int cxHi = int(boundedX ? clamp(floor(hi.x), 0.0, cellsX) : floor(hi.x));
  const float trim2 = radius * radius * 1.0001;
  uint count = 0u;
  for (int dz = -2; dz <= 2; ++dz) {
    const float gz = hemo_cell_gap(c.z + dz, lo.z, hi.z, dims.z, grid.periodic.z) * cellM.z;
    const int z = hemo_grid_step(c.z, dz, dims.z, grid.periodic.z);
    if (z < 0 || gz * gz >= trim2) {
      continue;
    }
    // The plane's five rows (x fastest, so rows yLo .. yHi of plane z are one block of cells):
    // a part with no particle in the block is skipped in all of them. Boundary particles list
    // fluid only, and most sit far from it (a tank's walls); most fluid particles sit far from
    // any boundary particle. Two texel fetches per plane save two per row and part.
    int yLo = c.y - 2;
    int yHi = c.y + 2;
    if (grid.periodic.y != 0u && (yLo < 0 || yHi >= int(dims.y))) {
      yLo = 0;  // the rows wrap: the whole plane
      yHi = int(dims.y) - 1;
    }
    yLo = clamp(yLo, 0, int(dims.y) - 1);
    yHi = clamp(yHi, 0, int(dims.y) - 1);
    const uint planeFirst = hemo_cell_linear(ivec3(0, yLo, z), dims);
    const uint planeLast = hemo_cell_linear(ivec3(hiX, yHi, z), dims);
    const uint tested = fluid ? cellCount : 0u;  // fluid: the boundary part; boundary: the fluid part
    const bool occupied = texelFetch(cellStart, int(tested + planeFirst)).x != texelFetch(cellStart, int(tested + planeLast + 1u)).x;
    if (!fluid && !occupied) {
      continue;
    }
    const uint parts = fluid && occupied ? 2u : 1u;
    for (int dy = -2; dy <= 2; ++dy) {
      const float gy = hemo_cell_gap(c.y + dy, lo.y, hi.y, dims.y, grid.periodic.y) * cellM.y;
      const float rest2 = trim2 - gy * gy - gz * gz;
      const int y = hemo_grid_step(c.y, dy, dims.y, grid.periodic.y);
      if (y < 0 || rest2 <= 0.0) {
        continue;
      }
      const float reach = sqrt(rest2) * grid.invCell.x;
      float xLoF = lo.x - reach;
      float xHiF = hi.x + reach;
#ifdef HEMO_LIST_POINTS
      // The union of the points' own trimmed ranges: the box's corner nearest the row is
      // nearer than any one point (a cluster's row group scans 14% fewer candidates).
      xLoF = 3.0e38;
      xHiF = -3.0e38;
      for (uint m = 0u; m < HEMO_LIST_POINTS; ++m) {
        const vec3 p = gListPoints[m];
        const float py = hemo_cell_gap(c.y + dy, p.y, p.y, dims.y, grid.periodic.y) * cellM.y;
        const float pz = hemo_cell_gap(c.z + dz, p.z, p.z, dims.z, grid.periodic.z) * cellM.z;
        const float pr2 = trim2 - py * py - pz * pz;
        const bool reaches = (gListPointMask & (1u << m)) != 0u && pr2 > 0.0;
        const float pr = sqrt(max(pr2, 0.0)) * grid.invCell.x;
        xLoF = reaches ? min(xLoF, p.x - pr) : xLoF;
        xHiF = reaches ? max(xHiF, p.x + pr) : xHiF;
      }
      if (xLoF > xHiF) {
        continue;
      }
#endif
      if (boundedX) {  // the edge cells hold the particles clamped into them
        xLoF = clamp(xLoF, 0.0, cellsX);
        xHiF = clamp(xHiF, 0.0, cellsX);
      }
      int xLo = int(floor(xLoF));
      int xHi = int(floor(xHiF));
      xLo = max(xLo, cxLo - reachX);
      xHi = min(xHi, min(cxHi + reachX, xLo + hiX));  // never a cell twice round a periodic x axis
      // The x-cells [xLo, xHi] as up to two contiguous ranges on the grid (the second, empty
      // unless a periodic x axis wraps, holds the cells past the seam).
      ivec2 xr[2];
      xr[0] = ivec2(max(xLo, 0), min(xHi, hiX));
      xr[1] = xLo < 0 ? ivec2(xLo + int(dims.x), hiX) : ivec2(0, xHi - int(dims.x));
      const int segments = grid.periodic.x != 0u ? 2 : 1;
      for (int s = 0; s < segments; ++s) {
        if (xr[s].x > xr[s].y) {
          continue;
        }
        const uint first = hemo_cell_linear(ivec3(xr[s].x, y, z), dims);
        const uint last = hemo_cell_linear(ivec3(xr[s].y, y, z), dims);
        for (uint part = 0u; part < parts; ++part) {
          // part 0: the fluid, plain slots; part 1: boundary and wall particles, marked
          const uint base = part * cellCount;
          const uint jBegin = texelFetch(cellStart, int(base + first)).x;
          const uint jEnd = texelFetch(cellStart, int(base + last + 1u)).x;
          if (jBegin < jEnd) {
            gRanges[count] = uvec2(jBegin, jEnd | (part == 0u ? 0u : HEMO_LIST_BOUNDARY_BIT));
            ++count;
          }
        }
      }
    }
  }
  return count;
}
