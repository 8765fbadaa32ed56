// The wall's surface for drawing (hemo/sim/wall_surface.hpp).
#include "hemo/sim/wall_surface.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <tuple>
#include <unordered_map>

namespace hemo::sim {

namespace {

std::uint64_t edgeKey(std::uint32_t a, std::uint32_t b) {
  return (std::uint64_t(std::min(a, b)) << 32) | std::max(a, b);
}

}  // namespace

std::vector<std::uint32_t> wallSurfaceTriangles(const std::vector<GpuSpring>& springs,
                                                const std::vector<std::uint32_t>& frames,
                                                const std::vector<glm::vec4>& positions, glm::vec3 period,
                                                const std::vector<glm::vec3>& normals) {
  const std::size_t points = frames.size() / 2;
  std::unordered_map<std::uint64_t, std::uint32_t> springOf;
  std::vector<std::vector<std::uint32_t>> neighbours(points);
  springOf.reserve(springs.size());
  for (std::uint32_t k = 0; k < springs.size(); ++k) {
    const GpuSpring& s = springs[k];
    if (s.a >= points || s.b >= points || s.a == s.b) continue;
    springOf.emplace(edgeKey(s.a, s.b), k);
    neighbours[s.a].push_back(s.b);
    neighbours[s.b].push_back(s.a);
  }
  for (auto& n : neighbours) std::sort(n.begin(), n.end());
  const auto offset = [&](std::uint32_t from, std::uint32_t to) {
    glm::dvec3 d = glm::dvec3(positions[to]) - glm::dvec3(positions[from]);
    for (int a = 0; a < 3; ++a) {
      if (period[a] > 0.0f) d[a] -= double(period[a]) * std::round(d[a] / double(period[a]));
    }
    return d;
  };
  // A point's normal into the fluid: as built when given, else from its frame. Zero: none.
  std::vector<glm::dvec3> normal(points, glm::dvec3(0.0));
  for (std::uint32_t x = 0; x < points; ++x) {
    if (x < normals.size() && glm::length(glm::dvec3(normals[x])) > 0.0) {
      normal[x] = glm::normalize(glm::dvec3(normals[x]));
      continue;
    }
    const std::uint32_t a = frames[2 * x], b = frames[2 * x + 1];
    if (a == WallPoint::kNoFrame || b == WallPoint::kNoFrame || a >= points || b >= points) continue;
    const glm::dvec3 n = glm::cross(offset(x, a), offset(x, b));
    if (glm::length(n) > 0.0) normal[x] = glm::normalize(n);
  }
  // The outermost layer: points with a normal and no spring neighbour of the same wall (its
  // normal within about 25 degrees) farther out, against the normal, than half the spring's
  // length. Within a layer a neighbour lies level or, on a convex wall, inward; the next
  // layer's lie out by about a spacing. Where two walls join (an aneurysm's sac on its
  // parent tube) a point of one may link to the other's points farther out: those do not
  // count, or the outer layer would open along the seam.
  std::vector<char> outermost(points, 0);
  for (std::uint32_t x = 0; x < points; ++x) {
    if (!(glm::length(normal[x]) > 0.0)) continue;
    outermost[x] = 1;
    for (std::uint32_t y : neighbours[x]) {
      const glm::dvec3 d = offset(x, y);
      if (glm::dot(normal[x], normal[y]) > 0.9 && glm::dot(d, -normal[x]) > 0.5 * glm::length(d)) {
        outermost[x] = 0;
        break;
      }
    }
  }
  // Candidates: triangles of three springs between outermost points that lie in the wall
  // (their plane within about 45 degrees of each corner's tangent plane), shortest longest
  // edge first, ties by ids.
  struct Candidate {
    double longest;
    std::array<std::uint32_t, 3> ids;  // ascending
  };
  std::vector<Candidate> candidates;
  for (std::uint32_t x = 0; x < points; ++x) {
    if (!outermost[x]) continue;
    const std::vector<std::uint32_t>& nx = neighbours[x];
    for (std::size_t i = 0; i < nx.size(); ++i) {
      const std::uint32_t y = nx[i];
      if (y <= x || !outermost[y]) continue;
      for (std::size_t j = i + 1; j < nx.size(); ++j) {
        const std::uint32_t z = nx[j];
        if (!outermost[z] || !springOf.count(edgeKey(y, z))) continue;
        const glm::dvec3 e1 = offset(x, y), e2 = offset(x, z);
        const glm::dvec3 n = glm::cross(e1, e2);
        const double area2 = glm::length(n);
        if (!(area2 > 0.0)) continue;
        bool inWall = true;
        for (std::uint32_t c : {x, y, z}) inWall = inWall && std::abs(glm::dot(n, normal[c])) > 0.4 * area2;
        if (!inWall) continue;
        const double longest = std::max({glm::length(e1), glm::length(e2), glm::length(e2 - e1)});
        candidates.push_back({longest, {x, y, z}});
      }
    }
  }
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& p, const Candidate& q) {
    return std::tie(p.longest, p.ids) < std::tie(q.longest, q.ids);
  });
  // Greedy: a triangle is taken unless one of its edges already has a taken triangle on the
  // same side (in the wall's tangent plane at the edge). Each edge ends with at most one
  // triangle on each side: the surface is a manifold, and of the two ways to split a square
  // the first taken excludes the other.
  std::unordered_map<std::uint64_t, std::uint8_t> sides;  // bit 0: left of (min, max), bit 1: right
  const auto sideOf = [&](std::uint32_t u, std::uint32_t v, std::uint32_t w) {
    const std::uint32_t lo = std::min(u, v), hi = std::max(u, v);
    const glm::dvec3 n = normal[lo] + normal[hi];
    return glm::dot(glm::cross(offset(lo, hi), offset(lo, w)), n) > 0.0 ? std::uint8_t(1) : std::uint8_t(2);
  };
  std::vector<std::uint32_t> out;
  for (const Candidate& c : candidates) {
    const auto [x, y, z] = c.ids;
    const std::array<std::tuple<std::uint32_t, std::uint32_t, std::uint32_t>, 3> edges{
        std::tuple{x, y, z}, std::tuple{y, z, x}, std::tuple{z, x, y}};
    bool free = true;
    std::array<std::uint8_t, 3> side{};
    for (int e = 0; e < 3; ++e) {
      const auto [u, v, w] = edges[e];
      side[e] = sideOf(u, v, w);
      const auto it = sides.find(edgeKey(u, v));
      if (it != sides.end() && (it->second & side[e])) free = false;
    }
    if (!free) continue;
    for (int e = 0; e < 3; ++e) sides[edgeKey(std::get<0>(edges[e]), std::get<1>(edges[e]))] |= side[e];
    // Wound so that (b - a) x (c - a) points into the fluid.
    std::array<std::uint32_t, 3> t{x, y, z};
    if (glm::dot(glm::cross(offset(x, y), offset(x, z)), normal[x] + normal[y] + normal[z]) < 0.0) std::swap(t[1], t[2]);
    out.insert(out.end(), {t[0], t[1], t[2], springOf.at(edgeKey(t[0], t[1])), springOf.at(edgeKey(t[1], t[2])),
                           springOf.at(edgeKey(t[2], t[0]))});
  }
  return out;
}

}  // namespace hemo::sim
