#include "hemo/surface/case_table.hpp"

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace hemo::surface {
namespace {

glm::dvec3 cornerPosition(int c) { return {double(c & 1), double((c >> 1) & 1), double((c >> 2) & 1)}; }

std::array<CubeEdge, kCubeEdgeCount> makeEdges() {
  std::array<CubeEdge, kCubeEdgeCount> edges{};
  for (int k = 0; k < 4; ++k) {
    const int lo = k & 1, hi = (k >> 1) & 1;
    const auto x = std::uint8_t(2 * lo + 4 * hi);  // edge y + 2z
    edges[k] = {x, std::uint8_t(x + 1), 0};
    const auto y = std::uint8_t(lo + 4 * hi);  // edge 4 + x + 2z
    edges[4 + k] = {y, std::uint8_t(y + 2), 1};
    const auto z = std::uint8_t(lo + 2 * hi);  // edge 8 + x + 2y
    edges[8 + k] = {z, std::uint8_t(z + 4), 2};
  }
  return edges;
}

int edgeBetween(int c1, int c2) {
  const auto& edges = cubeEdges();
  for (int e = 0; e < kCubeEdgeCount; ++e) {
    if ((edges[e].a == c1 && edges[e].b == c2) || (edges[e].a == c2 && edges[e].b == c1)) return e;
  }
  throw std::logic_error("corners " + std::to_string(c1) + " and " + std::to_string(c2) + " share no edge");
}

glm::dvec3 edgeMidpoint(int e) {
  const CubeEdge& edge = cubeEdges()[e];
  return 0.5 * (cornerPosition(edge.a) + cornerPosition(edge.b));
}

// Smallest angle (radians) of the triangle with these corners.
double smallestAngle(const glm::dvec3& p, const glm::dvec3& q, const glm::dvec3& r) {
  const glm::dvec3 pts[3] = {p, q, r};
  double best = 4.0;
  for (int k = 0; k < 3; ++k) {
    const glm::dvec3 u = glm::normalize(pts[(k + 1) % 3] - pts[k]);
    const glm::dvec3 v = glm::normalize(pts[(k + 2) % 3] - pts[k]);
    best = std::min(best, std::acos(std::clamp(glm::dot(u, v), -1.0, 1.0)));
  }
  return best;
}

struct Segment {
  int from = 0, to = 0;  // cube edges
};

// The oriented contour segments of case `cube` on every face.
std::vector<Segment> faceSegments(int cube) {
  const auto inside = [cube](int c) { return ((cube >> c) & 1) != 0; };
  const auto& edges = cubeEdges();
  std::vector<Segment> segments;
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    for (int side = 0; side < 2; ++side) {
      // The face's corners in cyclic order, and the edge from each to the next.
      int q[4];
      const int uv[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
      for (int k = 0; k < 4; ++k) q[k] = (side << axis) | (uv[k][0] << u) | (uv[k][1] << v);
      int e[4];
      for (int k = 0; k < 4; ++k) e[k] = edgeBetween(q[k], q[(k + 1) % 4]);

      std::vector<Segment> here;
      std::vector<int> crossing;
      for (int k = 0; k < 4; ++k) {
        if (inside(q[k]) != inside(q[(k + 1) % 4])) crossing.push_back(e[k]);
      }
      if (crossing.size() == 2) {
        here.push_back({crossing[0], crossing[1]});
      } else if (crossing.size() == 4) {
        // Inside corners on a diagonal: cut each inside corner off on its own.
        if (inside(q[0])) {
          here.push_back({e[3], e[0]});
          here.push_back({e[1], e[2]});
        } else {
          here.push_back({e[0], e[1]});
          here.push_back({e[2], e[3]});
        }
      }

      glm::dvec3 normal(0.0);
      normal[axis] = side ? 1.0 : -1.0;
      for (Segment s : here) {
        const glm::dvec3 a = edgeMidpoint(s.from), b = edgeMidpoint(s.to);
        const glm::dvec3 left = glm::cross(b - a, normal);
        const auto insideEnd = [&](int edge) {
          return cornerPosition(inside(edges[edge].a) ? edges[edge].a : edges[edge].b);
        };
        const double score = glm::dot(left, insideEnd(s.from) - a) + glm::dot(left, insideEnd(s.to) - a);
        if (score < 0.0) std::swap(s.from, s.to);
        segments.push_back(s);
      }
    }
  }
  return segments;
}

// True when cube edges e1 and e2 lie on one face of the cube: a chord between their
// vertices would lie in that face, where the neighbouring cube draws its own contour.
bool onCommonFace(int e1, int e2) {
  const auto& edges = cubeEdges();
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      const auto on = [&](int c) { return ((c >> axis) & 1) == side; };
      if (on(edges[e1].a) && on(edges[e1].b) && on(edges[e2].a) && on(edges[e2].b)) return true;
    }
  }
  return false;
}

// Triangulates a closed contour loop (cube edges in winding order). Among all triangulations
// whose chords stay off the cube's faces, the one with the largest smallest angle (judged
// with edge midpoints), by dynamic programming over the loop's intervals. Triangles keep the
// loop's winding.
std::vector<int> triangulateLoop(const std::vector<int>& loop, int cube) {
  const int n = int(loop.size());
  if (n < 3) throw std::logic_error("case " + std::to_string(cube) + ": a contour loop of " + std::to_string(n));
  const double none = -1.0;
  // best[i][j]: best smallest angle of the sub-polygon i..j (j > i + 1), none if impossible.
  std::vector<std::vector<double>> best(n, std::vector<double>(n, 4.0));
  std::vector<std::vector<int>> apex(n, std::vector<int>(n, -1));
  const auto chordOk = [&](int i, int j) {
    return j - i == 1 || (i == 0 && j == n - 1) || !onCommonFace(loop[i], loop[j]);
  };
  for (int len = 2; len < n; ++len) {
    for (int i = 0; i + len < n; ++i) {
      const int j = i + len;
      best[i][j] = none;
      if (!chordOk(i, j)) continue;
      for (int k = i + 1; k < j; ++k) {
        const double left = k - i >= 2 ? best[i][k] : 4.0;
        const double right = j - k >= 2 ? best[k][j] : 4.0;
        if (left == none || right == none) continue;
        const double angle = smallestAngle(edgeMidpoint(loop[i]), edgeMidpoint(loop[k]), edgeMidpoint(loop[j]));
        const double score = std::min({left, right, angle});
        if (score > best[i][j] + 1e-12) {
          best[i][j] = score;
          apex[i][j] = k;
        }
      }
    }
  }
  if (best[0][n - 1] == none) {
    throw std::logic_error("case " + std::to_string(cube) + ": a contour loop has no triangulation off the faces");
  }
  std::vector<int> triangles;
  std::vector<std::pair<int, int>> stack{{0, n - 1}};
  while (!stack.empty()) {
    const auto [i, j] = stack.back();
    stack.pop_back();
    const int k = apex[i][j];
    triangles.insert(triangles.end(), {loop[i], loop[k], loop[j]});
    if (k - i >= 2) stack.push_back({i, k});
    if (j - k >= 2) stack.push_back({k, j});
  }
  return triangles;
}

}  // namespace

const std::array<CubeEdge, kCubeEdgeCount>& cubeEdges() {
  static const std::array<CubeEdge, kCubeEdgeCount> edges = makeEdges();
  return edges;
}

CaseTable buildCaseTable() {
  CaseTable table;
  for (int cube = 0; cube < 256; ++cube) {
    const std::vector<Segment> segments = faceSegments(cube);
    int next[kCubeEdgeCount];
    int incoming[kCubeEdgeCount] = {};
    std::fill(std::begin(next), std::end(next), -1);
    for (const Segment& s : segments) {
      if (next[s.from] != -1) {
        throw std::logic_error("case " + std::to_string(cube) + ": edge " + std::to_string(s.from) +
                               " starts two contour segments");
      }
      next[s.from] = s.to;
      ++incoming[s.to];
    }
    for (int e = 0; e < kCubeEdgeCount; ++e) {
      if ((next[e] == -1) != (incoming[e] == 0) || incoming[e] > 1) {
        throw std::logic_error("case " + std::to_string(cube) + ": the contour does not close at edge " +
                               std::to_string(e));
      }
    }

    std::vector<std::uint8_t> triangles;
    bool used[kCubeEdgeCount] = {};
    for (int start = 0; start < kCubeEdgeCount; ++start) {
      if (next[start] == -1 || used[start]) continue;
      std::vector<int> loop;
      for (int e = start; !used[e]; e = next[e]) {
        used[e] = true;
        loop.push_back(e);
      }
      for (const int v : triangulateLoop(loop, cube)) triangles.push_back(std::uint8_t(v));
    }
    const int count = int(triangles.size() / 3);
    if (count > kMaxTrianglesPerCube) {
      throw std::logic_error("case " + std::to_string(cube) + " needs " + std::to_string(count) + " triangles");
    }
    table.triangleCount[cube] = std::uint8_t(count);
    std::copy(triangles.begin(), triangles.end(), table.edges[cube].begin());
    table.maxTriangles = std::max(table.maxTriangles, count);
  }
  return table;
}

std::vector<std::uint32_t> packCaseTable(const CaseTable& table) {
  static_assert(3 * kMaxTrianglesPerCube <= 24, "three words of eight 4-bit edges");
  std::vector<std::uint32_t> packed(256 * 4, 0u);
  for (int cube = 0; cube < 256; ++cube) {
    packed[4 * cube] = table.triangleCount[cube];
    for (int k = 0; k < 3 * table.triangleCount[cube]; ++k) {
      packed[4 * cube + 1 + k / 8] |= std::uint32_t(table.edges[cube][k]) << (4 * (k % 8));
    }
  }
  return packed;
}

}  // namespace hemo::surface
