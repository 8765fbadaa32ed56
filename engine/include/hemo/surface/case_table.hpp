#pragma once
// The marching-cubes case table, derived by hemo's own code (engine/surface/case_table.cpp)
// instead of copied from the literature.
//
// Cube conventions (shared with compute_shaders/mc/ and the CPU reference):
//   corner c = x + 2y + 4z for (x, y, z) in {0, 1}^3, at offset (x, y, z) voxels;
//   edges 0-3 run along x from corner 2y + 4z        (edge = y + 2z),
//   edges 4-7 run along y from corner x + 4z         (edge = 4 + x + 2z),
//   edges 8-11 run along z from corner x + 2y        (edge = 8 + x + 2y);
//   each edge goes from its lower corner a to its upper corner b = a + 1, 2 or 4.
//   Case index: bit c set when corner c is inside (field value > iso level).
//
// How a case is derived: on each of the cube's six faces the iso-contour is a set of
// segments joining the face's sign-changing edges. With two such edges there is one segment.
// With four (an ambiguous face, inside corners on a diagonal) the rule is always the same:
// the segments cut off the two inside corners. The rule depends only on the face's own corner
// signs, so the two cubes that share a face draw the same segments there; the surface is
// therefore watertight across cubes. Each segment is oriented so that, seen from outside the
// cube, the inside corners lie to its left; the segments then chain into closed loops around
// the surface patch. Each loop is triangulated without any chord lying in a cube face (such a
// chord would meet the neighbour's contour on that face and make the mesh non-manifold),
// choosing among those triangulations the one with the largest smallest angle (judged with
// edge midpoints). Triangles wind counter-clockwise seen
// from outside the surface (their normal points from inside to outside: down the field).
#include <array>
#include <cstdint>
#include <vector>

namespace hemo::surface {

inline constexpr int kCubeEdgeCount = 12;
// Enough for every case the face rule produces (checked when the table is built).
inline constexpr int kMaxTrianglesPerCube = 8;

struct CubeEdge {
  std::uint8_t a = 0;  // lower corner
  std::uint8_t b = 0;  // upper corner
  std::uint8_t axis = 0;
};

// The twelve edges in the order above.
const std::array<CubeEdge, kCubeEdgeCount>& cubeEdges();

struct CaseTable {
  // Triangles of each case; edges[c][3t .. 3t+2] are the cube edges carrying the vertices of
  // triangle t, in winding order.
  std::array<std::uint8_t, 256> triangleCount{};
  std::array<std::array<std::uint8_t, 3 * kMaxTrianglesPerCube>, 256> edges{};
  int maxTriangles = 0;  // over all cases
};

// Builds the table (pure; a few microseconds). Throws std::logic_error if a case's contour
// does not close, which would be a bug in the derivation.
CaseTable buildCaseTable();

// The table as the GPU reads it: 256 uvec4 (x = triangle count, y/z/w = the edge list, eight
// 4-bit edge numbers per word, first edge in the lowest bits).
std::vector<std::uint32_t> packCaseTable(const CaseTable& table);

}  // namespace hemo::surface
