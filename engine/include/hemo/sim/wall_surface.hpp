#pragma once
// The vessel wall as a surface for drawing (render::WallSurfaceView): triangles over the wall's
// outermost layer of points, each edge one of its springs, so that a triangle shows only while
// its three springs hold and the surface tears where springs broke.
//
// The outermost layer: the points with no spring neighbour of the same wall (normals within
// about 25 degrees) farther out, against the normal (which points into the fluid), than half
// that spring's length; within a layer a neighbour lies level or, on a convex wall, inward,
// and the next layer's lie a spacing out. (Where a sac joins its tube, a point of one may link
// to the other's points farther out; those do not count.) The triangles:
// every three mutually linked outermost points whose plane lies in the wall (within about 45
// degrees of each corner's tangent plane), taken greedily, shortest longest edge first, unless
// an edge already has a taken triangle on the same side. Each edge then has at most one
// triangle on each side (a manifold), and of the two ways to split a square of springs with
// both diagonals the first taken excludes the other. The outermost layer is what the eye sees;
// drawn translucent alone, it shows the blood without the layers' edges crossing.
#include "hemo/sim/wall.hpp"

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <cstdint>
#include <vector>

namespace hemo::sim {

// Words per triangle in wallSurfaceTriangles' output: ids (a, b, c), then the springs along
// (a, b), (b, c), (c, a).
inline constexpr std::uint32_t kWallTriangleWords = 6;

// `springs` as the GPU holds them (a < b), `frames` two ids per point id (frame A, frame B;
// WallPoint::kNoFrame without), `positions` by particle id (xyz m), `period` (m) on periodic
// axes and 0 elsewhere (offsets are taken to the minimum image). `normals` (optional, by point
// id, into the fluid): the wall's normals as built, which say what is outward better than the
// frames' cross products (used without them), which lean by up to 60 degrees where the layout
// is irregular (an aneurysm's Fibonacci sphere). Each triangle is wound so that
// (b - a) x (c - a) points into the fluid.
std::vector<std::uint32_t> wallSurfaceTriangles(const std::vector<GpuSpring>& springs,
                                                const std::vector<std::uint32_t>& frames,
                                                const std::vector<glm::vec4>& positions, glm::vec3 period,
                                                const std::vector<glm::vec3>& normals = {});

}  // namespace hemo::sim
