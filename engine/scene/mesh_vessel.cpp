#include "hemo/scene/mesh_vessel.hpp"

#include "hemo/scene/aneurysm.hpp"
#include "interface/sph.h"
#include "point_bins.hpp"
#include "wall_links.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <random>
#include <sstream>
#include <stdexcept>

namespace hemo::scene {

namespace {

constexpr double kLinkRadius = 1.75;      // spacings: springs join wall points nearer than this (about as many per point as the tube's lattice)
constexpr double kCandidateStep = 0.25;   // spacings between a layer's candidate points
constexpr double kFluidClearance = 0.45;  // spacings: no fluid this near a wall point
constexpr double kLayerClearance = 0.5;   // a layer's point at least this x its offset from the surface

std::string at(glm::dvec3 p) {
  std::ostringstream s;
  s.precision(6);
  s << "(" << p.x << ", " << p.y << ", " << p.z << ") m";
  return s.str();
}

double cross2(glm::dvec2 a, glm::dvec2 b) { return a.x * b.y - a.y * b.x; }

// The point of triangle abc nearest to p (by the region of the triangle's plane p projects
// into: a vertex, an edge or the face).
glm::dvec3 closestOnTriangle(glm::dvec3 p, glm::dvec3 a, glm::dvec3 b, glm::dvec3 c) {
  const glm::dvec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  if (d1 <= 0.0 && d2 <= 0.0) return a;
  const glm::dvec3 bp = p - b;
  const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  if (d3 >= 0.0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return a + ab * (d1 / (d1 - d3));
  const glm::dvec3 cp = p - c;
  const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  if (d6 >= 0.0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

// A uniform grid of cells over a box, each listing the items whose boxes overlap it.
template <int D>
struct Grid {
  glm::dvec3 origin{0.0};
  double cell = 1.0;
  std::array<long, 3> n{1, 1, 1};
  std::vector<std::vector<std::uint32_t>> items;
  void init(glm::dvec3 lo, glm::dvec3 hi, double cellSize) {
    origin = lo;
    cell = cellSize;
    for (int a = 0; a < 3; ++a) n[a] = a < D ? std::max(1L, long(std::ceil((hi[a] - lo[a]) / cell)) + 1) : 1;
    items.assign(std::size_t(n[0] * n[1] * n[2]), {});
  }
  long clampIndex(int a, double v) const { return std::clamp(long(std::floor((v - origin[a]) / cell)), 0L, n[a] - 1); }
  void add(std::uint32_t item, glm::dvec3 lo, glm::dvec3 hi) {
    std::array<long, 3> i0{0, 0, 0}, i1{0, 0, 0};
    for (int a = 0; a < D; ++a) i0[a] = clampIndex(a, lo[a]), i1[a] = clampIndex(a, hi[a]);
    for (long x = i0[0]; x <= i1[0]; ++x)
      for (long y = i0[1]; y <= i1[1]; ++y)
        for (long z = i0[2]; z <= i1[2]; ++z) items[std::size_t((x * n[1] + y) * n[2] + z)].push_back(item);
  }
};

// Spreads a layer's points evenly over its surface (the triangles `tris` on `verts`, with
// unit `normals` at the corners): the greedy sample leaves holes up to its exclusion radius
// wide, where the fluid could slip between wall points; a few rounds of mutual repulsion
// between points nearer than 1.5 radii (or one bin cell; each moved by at most a quarter radius, then put back
// on the nearest point of the surface) even them out towards a triangular lattice. A move
// that would leave `allowed` points (clear of the lumen) is not made. `empty` supplies the
// binning (periodic or not) for the rounds.
template <class Allowed, class Wrap, class Bins>
void relaxOnSurface(std::vector<glm::dvec3>& pts, std::vector<glm::dvec3>& normals, const std::vector<glm::dvec3>& verts,
                    const std::vector<std::array<std::uint32_t, 3>>& tris, const std::vector<glm::dvec3>& cornerNormals, double radius,
                    Allowed allowed, Wrap wrap, const Bins& empty, double binCell) {
  constexpr int kRounds = 24;
  glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
  double edges = 0.0;
  for (const auto& t : tris) {
    for (std::uint32_t v : t) lo = glm::min(lo, verts[v]), hi = glm::max(hi, verts[v]);
    edges += glm::length(verts[t[1]] - verts[t[0]]);
  }
  // A point moves at most a quarter radius off the surface: its projection lies within 0.3.
  const double search = 0.3 * radius;
  Grid<3> grid;
  grid.init(lo - radius, hi + radius, std::max(2.0 * edges / double(tris.size()), search));
  for (std::size_t i = 0; i < tris.size(); ++i) {
    const auto& t = tris[i];
    grid.add(std::uint32_t(i), glm::min(verts[t[0]], glm::min(verts[t[1]], verts[t[2]])), glm::max(verts[t[0]], glm::max(verts[t[1]], verts[t[2]])));
  }
  // The nearest point of the surface within `search` of p (and the normal there), if any.
  auto project = [&](glm::dvec3 p, glm::dvec3& at, glm::dvec3& normal) {
    double best = search;
    bool found = false;
    std::array<long, 3> i0{}, i1{};
    for (int a = 0; a < 3; ++a) i0[a] = grid.clampIndex(a, p[a] - search), i1[a] = grid.clampIndex(a, p[a] + search);
    for (long x = i0[0]; x <= i1[0]; ++x)
      for (long y = i0[1]; y <= i1[1]; ++y)
        for (long z = i0[2]; z <= i1[2]; ++z)
          for (std::uint32_t ti : grid.items[std::size_t((x * grid.n[1] + y) * grid.n[2] + z)]) {
            const auto& t = tris[ti];
            const glm::dvec3 a = verts[t[0]], b = verts[t[1]], c = verts[t[2]];
            const glm::dvec3 cp = closestOnTriangle(p, a, b, c);
            const double d = glm::length(p - cp);
            if (d >= best) continue;
            best = d;
            found = true;
            at = cp;
            // Barycentric weights of the closest point, from the sub-triangles' areas.
            const glm::dvec3 n = glm::cross(b - a, c - a);
            const double n2 = glm::dot(n, n);
            const double wa = glm::dot(glm::cross(b - cp, c - cp), n) / n2, wb = glm::dot(glm::cross(c - cp, a - cp), n) / n2;
            normal = glm::normalize(wa * cornerNormals[t[0]] + wb * cornerNormals[t[1]] + (1.0 - wa - wb) * cornerNormals[t[2]]);
          }
    return found;
  };
  const double reach = std::min(1.5 * radius, binCell);  // (the bins find neighbours within one cell)
  for (int round = 0; round < kRounds; ++round) {
    Bins bins = empty;
    for (std::size_t i = 0; i < pts.size(); ++i) bins.add(pts[i], std::uint32_t(i));
    std::vector<glm::dvec3> moved = pts, movedNormals = normals;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      glm::dvec3 push(0.0);
      bins.near(pts[i], reach, [&](std::uint32_t j, glm::dvec3 d) {
        const double len = glm::length(d);
        if (j != i && len > 0.0) push -= (reach - len) / reach * d / len;
      });
      glm::dvec3 step = 0.2 * radius * push;
      const double len = glm::length(step);
      if (len > 0.25 * radius) step *= 0.25 * radius / len;
      glm::dvec3 at, normal;
      if (project(wrap(pts[i] + step), at, normal) && allowed(at)) {
        moved[i] = wrap(at);
        movedNormals[i] = normal;
      }
    }
    pts = std::move(moved);
    normals = std::move(movedNormals);
  }
}

}  // namespace

// The closed surface (the mesh and its caps) binned over (y, z) for the ray along x, and the
// mesh's own triangles binned in 3D for distances.
struct VesselMesh::Index {
  std::vector<glm::dvec3> points;                      // the mesh's vertices, then one per cap
  std::vector<std::array<std::uint32_t, 3>> closed;    // the mesh's triangles, then the caps'
  Grid<3> columns;  // over (y, z) in axes 0 and 1 of the grid: (y, z, unused)
  Grid<3> cells;    // the mesh's triangles, 3D

  // Signed crossings of the closed surface by the line through (y, z) along x: (x, +1) where
  // it leaves the lumen going +x, (x, -1) where it enters, sorted by x.
  std::vector<std::pair<double, int>> crossings(double y, double z) const {
    std::vector<std::pair<double, int>> out;
    const long cy = columns.clampIndex(0, y), cz = columns.clampIndex(1, z);
    const glm::dvec2 q(y, z);
    for (std::uint32_t t : columns.items[std::size_t(cy * columns.n[1] + cz)]) {
      const glm::dvec3 A = points[closed[t][0]], B = points[closed[t][1]], C = points[closed[t][2]];
      const glm::dvec2 a(A.y, A.z), b(B.y, B.z), c(C.y, C.z);
      const double twice = cross2(b - a, c - a);
      if (twice == 0.0) continue;  // seen edge-on: the ray crosses its neighbours instead
      const int sign = twice > 0.0 ? 1 : -1;
      // Edges taken counter-clockwise in (y, z); a point exactly on an edge belongs to the
      // side that owns the edge (it runs up in y, or along -z at constant y), so of two
      // triangles that share an edge (and run it opposite ways) exactly one counts it.
      bool in = true;
      const glm::dvec2 corners[3] = {a, b, c};
      double w[3];
      for (int k = 0; k < 3 && in; ++k) {
        glm::dvec2 u = corners[(k + 1) % 3], v = corners[(k + 2) % 3];
        if (sign < 0) std::swap(u, v);
        const double e = cross2(v - u, q - u);
        w[k] = sign * e;  // the barycentric weight of corner k, times twice the area
        if (e < 0.0) in = false;
        if (e == 0.0) {
          const glm::dvec2 d = v - u;
          in = d.x > 0.0 || (d.x == 0.0 && d.y < 0.0);
        }
      }
      if (!in) continue;
      const double x = (w[0] * A.x + w[1] * B.x + w[2] * C.x) / twice;
      out.emplace_back(x, sign);
    }
    std::sort(out.begin(), out.end());
    return out;
  }
};

VesselMesh::VesselMesh(io::TriangleMesh mesh) : mesh_(std::move(mesh)) {
  const auto& V = mesh_.vertices;
  const auto& T = mesh_.triangles;
  if (T.size() < 4) throw std::invalid_argument("the mesh has " + std::to_string(T.size()) + " triangles (a closed surface needs at least 4)");
  min_ = glm::dvec3(std::numeric_limits<double>::infinity());
  max_ = -min_;
  for (const auto& t : T)
    for (std::uint32_t v : t) {
      if (v >= V.size()) throw std::invalid_argument("a triangle refers to vertex " + std::to_string(v) + " of " + std::to_string(V.size()));
      min_ = glm::min(min_, V[v]);
      max_ = glm::max(max_, V[v]);
    }
  const double diag = glm::length(max_ - min_);
  // Zero-area triangles: no normal, and no side of the wall to put particles on.
  for (std::size_t i = 0; i < T.size(); ++i) {
    const glm::dvec3 a = V[T[i][0]], b = V[T[i][1]], c = V[T[i][2]];
    const double twice = glm::length(glm::cross(b - a, c - a));
    if (!(twice > 2e-12 * diag * diag)) {
      throw std::invalid_argument("triangle " + std::to_string(i) + " (corners " + at(a) + ", " + at(b) + ", " + at(c) +
                                  ") has zero area: remove it or merge its corners in the mesh");
    }
    area_ += 0.5 * twice;
  }
  // Edges: each shared by two triangles that run it opposite ways, or on a boundary (one).
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<std::pair<std::uint32_t, bool>>> edges;  // (lo, hi) -> (triangle, runs lo -> hi)
  for (std::size_t i = 0; i < T.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t u = T[i][k], v = T[i][(k + 1) % 3];
      edges[{std::min(u, v), std::max(u, v)}].emplace_back(std::uint32_t(i), u < v);
    }
  std::vector<std::uint32_t> parent(T.size());
  for (std::size_t i = 0; i < T.size(); ++i) parent[i] = std::uint32_t(i);
  auto root = [&](std::uint32_t i) {  // (iterative: a segmented vessel has up to millions of triangles)
    std::uint32_t r = i;
    while (parent[r] != r) r = parent[r];
    while (parent[i] != r) {
      const std::uint32_t up = parent[i];
      parent[i] = r;
      i = up;
    }
    return r;
  };
  std::map<std::uint32_t, std::uint32_t> next;  // boundary: the surface runs u -> v
  for (const auto& [key, users] : edges) {
    const std::string edge = "the edge from " + at(V[key.first]) + " to " + at(V[key.second]);
    if (users.size() > 2) {
      throw std::invalid_argument(edge + " is shared by " + std::to_string(users.size()) +
                                  " triangles (a non-manifold edge: a surface edge has one triangle on each side)");
    }
    if (users.size() == 2) {
      if (users[0].second == users[1].second) {
        throw std::invalid_argument("triangles " + std::to_string(users[0].first) + " and " + std::to_string(users[1].first) + " run " + edge +
                                    " the same way: their windings disagree (some normals point into the lumen, some out)");
      }
      parent[root(users[0].first)] = root(users[1].first);
      continue;
    }
    const std::uint32_t u = users[0].second ? key.first : key.second, v = users[0].second ? key.second : key.first;
    if (!next.emplace(u, v).second) {
      throw std::invalid_argument("two boundary loops touch at the vertex " + at(V[u]) + " (a non-manifold vertex)");
    }
  }
  std::size_t pieces = 0;
  for (std::size_t i = 0; i < T.size(); ++i) pieces += root(std::uint32_t(i)) == i;
  if (pieces > 1) throw std::invalid_argument("the mesh has " + std::to_string(pieces) + " separate pieces (a vessel is one connected surface)");

  // Boundary loops, each closed by a flat cap: a fan from the loop's mean point, its triangles
  // running the loop's edges the other way (so the closed surface's winding agrees).
  auto index = std::make_shared<Index>();
  index->points = V;
  index->closed = T;
  std::map<std::uint32_t, bool> used;
  for (const auto& [start, unused] : next) {
    (void)unused;
    if (used[start]) continue;
    MeshEnd end;
    std::uint32_t v = start;
    do {
      used[v] = true;
      end.loop.push_back(v);
      const auto it = next.find(v);
      if (it == next.end()) throw std::invalid_argument("the boundary edge at " + at(V[v]) + " does not close into a loop");
      v = it->second;
    } while (v != start && end.loop.size() <= next.size());
    glm::dvec3 mean(0.0);
    for (std::uint32_t u : end.loop) mean += V[u];
    mean /= double(end.loop.size());
    const auto apex = std::uint32_t(index->points.size());
    index->points.push_back(mean);
    glm::dvec3 vectorArea(0.0);
    for (std::size_t k = 0; k < end.loop.size(); ++k) {
      const std::uint32_t a = end.loop[k], b = end.loop[(k + 1) % end.loop.size()];
      index->closed.push_back({apex, b, a});
      vectorArea += 0.5 * glm::cross(V[b] - mean, V[a] - mean);
    }
    end.area = glm::length(vectorArea);
    if (!(end.area > 0.0)) throw std::invalid_argument("the boundary loop at " + at(mean) + " encloses no area");
    end.normal = vectorArea / end.area;
    glm::dvec3 centroid(0.0);
    double weight = 0.0;
    for (std::size_t k = 0; k < end.loop.size(); ++k) {
      const glm::dvec3 a = V[end.loop[k]], b = V[end.loop[(k + 1) % end.loop.size()]];
      const double w = 0.5 * glm::dot(glm::cross(b - mean, a - mean), end.normal);
      centroid += w * (mean + a + b) / 3.0;
      weight += w;
    }
    end.centroid = centroid / weight;
    end.radius = std::sqrt(end.area / std::numbers::pi);
    ends_.push_back(std::move(end));
  }
  // The closed volume (about the box's middle, for rounding): negative when the triangles
  // are wound inside out.
  const glm::dvec3 mid = 0.5 * (min_ + max_);
  for (const auto& t : index->closed) {
    volume_ += glm::dot(index->points[t[0]] - mid, glm::cross(index->points[t[1]] - mid, index->points[t[2]] - mid)) / 6.0;
  }
  if (volume_ < 0.0) {
    throw std::invalid_argument("the triangles' normals point into the lumen (the closed surface's volume is negative): reverse every triangle's winding");
  }
  if (!(volume_ > 1e-9 * diag * diag * diag)) throw std::invalid_argument("the closed surface encloses no volume");

  // Vertex normals, angle-weighted; at an end, in the cap's plane (the wall runs on straight
  // through the cut).
  normals_.assign(V.size(), glm::dvec3(0.0));
  for (const auto& t : T) {
    const glm::dvec3 n = glm::normalize(glm::cross(V[t[1]] - V[t[0]], V[t[2]] - V[t[0]]));
    for (int k = 0; k < 3; ++k) {
      const glm::dvec3 e1 = glm::normalize(V[t[(k + 1) % 3]] - V[t[k]]), e2 = glm::normalize(V[t[(k + 2) % 3]] - V[t[k]]);
      normals_[t[k]] += std::acos(std::clamp(glm::dot(e1, e2), -1.0, 1.0)) * n;
    }
  }
  for (const MeshEnd& e : ends_)
    for (std::uint32_t u : e.loop) normals_[u] -= glm::dot(normals_[u], e.normal) * e.normal;
  for (glm::dvec3& n : normals_) {
    const double len = glm::length(n);
    if (len > 0.0) n /= len;
  }

  // The indexes: about sqrt(triangles) columns a side; 3D cells of twice the mean edge, and at
  // least 1/64 of the box's diagonal (a query a few spacings wide visits few cells).
  const auto side = std::clamp(long(std::sqrt(double(index->closed.size()))), 1L, 512L);
  const double colCell = std::max({max_.y - min_.y, max_.z - min_.z, 1e-12}) / double(side);
  index->columns.init(glm::dvec3(min_.y, min_.z, 0.0), glm::dvec3(max_.y, max_.z, 0.0), colCell);
  for (std::size_t i = 0; i < index->closed.size(); ++i) {
    const auto& t = index->closed[i];
    glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
    for (std::uint32_t v : t) {
      const glm::dvec3 p(index->points[v].y, index->points[v].z, 0.0);
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
    index->columns.add(std::uint32_t(i), lo, hi);
  }
  double edgeSum = 0.0;
  for (const auto& t : T) edgeSum += glm::length(V[t[1]] - V[t[0]]);
  const double cell = std::max(2.0 * edgeSum / double(T.size()), diag / 64.0);
  index->cells.init(min_, max_, cell);
  for (std::size_t i = 0; i < T.size(); ++i) {
    const glm::dvec3 a = V[T[i][0]], b = V[T[i][1]], c = V[T[i][2]];
    index->cells.add(std::uint32_t(i), glm::min(a, glm::min(b, c)), glm::max(a, glm::max(b, c)));
  }
  index_ = std::move(index);
}

std::vector<std::pair<double, int>> VesselMesh::crossings(double y, double z) const { return index_->crossings(y, z); }

bool VesselMesh::inside(glm::dvec3 p) const {
  int count = 0;
  for (const auto& [x, sign] : crossings(p.y, p.z)) count += x > p.x ? sign : 0;
  return count != 0;
}

double VesselMesh::distance(glm::dvec3 p, double within) const {
  const Grid<3>& g = index_->cells;
  std::array<long, 3> lo{}, hi{};
  for (int a = 0; a < 3; ++a) {
    if (p[a] + within < min_[a] || p[a] - within > max_[a]) return within;
    lo[a] = g.clampIndex(a, p[a] - within);
    hi[a] = g.clampIndex(a, p[a] + within);
  }
  double best = within;
  const auto& V = mesh_.vertices;
  for (long x = lo[0]; x <= hi[0]; ++x)
    for (long y = lo[1]; y <= hi[1]; ++y)
      for (long z = lo[2]; z <= hi[2]; ++z)
        for (std::uint32_t t : g.items[std::size_t((x * g.n[1] + y) * g.n[2] + z)]) {
          const auto& tri = mesh_.triangles[t];
          best = std::min(best, glm::length(p - closestOnTriangle(p, V[tri[0]], V[tri[1]], V[tri[2]])));
        }
  return best;
}

MeshVesselBuild buildMeshVessel(const AneurysmSpec& spec) {
  if (!spec.mesh) throw std::invalid_argument("mesh vessel: no mesh");
  const VesselMesh& m = *spec.mesh;
  const TubeSpec& t = spec.tube;
  const double dp = t.spacing;
  if (!(dp > 0.0) || !std::isfinite(dp)) throw std::invalid_argument("spacing must be positive");
  if (t.layers < 1) throw std::invalid_argument("layers must be at least 1");
  if (!(t.pointMass > 0.0f)) throw std::invalid_argument("point mass must be positive");
  const glm::dvec3 size = m.max() - m.min();
  if (std::min({size.x, size.y, size.z}) < 4.0 * dp) {
    throw std::invalid_argument("the mesh is " + at(size) + " across, less than 4 particle spacings (" + std::to_string(4.0 * dp) +
                                " m) along an axis: too small for this resolution, or its unit is wrong");
  }
  const double x0 = t.x0, L = t.length;
  const double tol = 1e-3 * dp;
  if (t.periodic) {
    // Every end on one of the two planes, and the two planes' loops the same shape.
    std::vector<const MeshEnd*> low, high;
    for (const MeshEnd& e : m.ends()) {
      bool onLow = true, onHigh = true;
      for (std::uint32_t u : e.loop) {
        onLow = onLow && std::abs(m.surface().vertices[u].x - x0) <= tol;
        onHigh = onHigh && std::abs(m.surface().vertices[u].x - (x0 + L)) <= tol;
      }
      if (!onLow && !onHigh) {
        throw std::invalid_argument("the mesh's open end at " + at(e.centroid) + " does not lie on the periodic planes x = " +
                                    std::to_string(x0) + " or " + std::to_string(x0 + L) + " m");
      }
      (onLow ? low : high).push_back(&e);
    }
    if (low.size() != high.size()) throw std::invalid_argument("the mesh's ends on the two periodic planes do not pair up");
    for (const MeshEnd* a : low) {
      bool paired = false;
      for (const MeshEnd* b : high) {
        if (a->loop.size() != b->loop.size()) continue;
        bool same = true;
        for (std::uint32_t u : a->loop) {
          const glm::dvec3 p = m.surface().vertices[u];
          double best = std::numeric_limits<double>::infinity();
          for (std::uint32_t v : b->loop) {
            const glm::dvec3 q = m.surface().vertices[v];
            best = std::min(best, std::hypot(p.y - q.y, p.z - q.z));
          }
          same = same && best <= tol;
        }
        paired = paired || same;
      }
      if (!paired) {
        throw std::invalid_argument("the mesh's end at " + at(a->centroid) + " has no end of the same shape on the plane x = " +
                                    std::to_string(x0 + L) + " m (a periodic vessel's ends must match across the seam)");
      }
    }
  } else if (!m.ends().empty() && !spec.openEnds) {
    throw std::invalid_argument("the mesh has " + std::to_string(m.ends().size()) +
                                " open ends, which need a periodic x axis with the ends on its two planes, or open inlets and "
                                "outlets (AneurysmSpec::openEnds); or close them in the mesh");
  }
  const double period = t.periodic ? L : 1e3 * (glm::length(size) + dp);
  const double binX0 = t.periodic ? x0 : m.min().x - 10.0 * dp;
  auto wrap = [&](glm::dvec3 p) {
    if (t.periodic) {
      p.x -= L * std::floor((p.x - x0) / L);
      if (!(float(p.x) < float(x0 + L))) p.x = x0;  // (a point a rounding below the end is at the start)
    }
    return p;
  };

  const auto& V = m.surface().vertices;
  const auto& T = m.surface().triangles;
  const auto& N = m.vertexNormals();
  MeshVesselBuild b;
  std::vector<glm::dvec3> pos, inward;
  Bins wallBins(binX0, period, kLinkRadius * dp);
  for (std::uint32_t l = 0; l < t.layers; ++l) {
    const double offset = (l + 0.5) * dp;
    std::vector<glm::dvec3> q(V.size());
    for (std::size_t v = 0; v < V.size(); ++v) q[v] = V[v] + offset * N[v];
    // Candidates: a barycentric grid a quarter spacing apart on every triangle of the layer
    // (a triangle smaller than that: its centroid).
    struct Candidate {
      glm::dvec3 p, n, moved;  // wrapped into the period; the normal; as moved (unwrapped)
      std::int8_t state;       // 0 not checked yet, 1 clear of the surface, -1 not
    };
    std::vector<Candidate> cand;
    for (const auto& tri : T) {
      const glm::dvec3 a = q[tri[0]], bb = q[tri[1]], c = q[tri[2]];
      const double edge = std::max({glm::length(bb - a), glm::length(c - bb), glm::length(a - c)});
      const auto n = std::max(1L, long(std::ceil(edge / (kCandidateStep * dp))));
      auto add = [&](double u, double v) {
        const double w = 1.0 - u - v;
        const glm::dvec3 p = u * a + v * bb + w * c;
        cand.push_back({wrap(p), glm::normalize(u * N[tri[0]] + v * N[tri[1]] + w * N[tri[2]]), p, 0});
      };
      if (n == 1 && edge < kCandidateStep * dp) {
        add(1.0 / 3.0, 1.0 / 3.0);
        continue;
      }
      for (long i = 0; i <= n; ++i)
        for (long j = 0; i + j <= n; ++j) add(double(i) / n, double(j) / n);
    }
    // Where the surface curves more tightly than the offset (a concave fold), the moved layer
    // crosses itself: only points that stand clear of the surface are kept. Checked when a
    // candidate would be kept, once (most never come to it).
    auto clear = [&](Candidate& k) {
      if (k.state == 0) k.state = m.distance(k.moved, offset) < kLayerClearance * offset || m.inside(k.moved) ? -1 : 1;
      return k.state > 0;
    };
    // A fixed pseudo-random order (Fisher-Yates with the standard's exactly specified engine).
    std::mt19937_64 rng(0x6d657368u + l);
    for (std::size_t i = cand.size(); i > 1; --i) std::swap(cand[i - 1], cand[rng() % i]);
    // Every layer holds as many points as the lumen's surface has dp^2 (as the analytic tube
    // puts the same ring on every layer), so the outer layers are a little sparser.
    const double target = m.area() / (dp * dp);
    auto sample = [&](double radius, std::vector<std::uint32_t>* kept) {
      Bins bins(binX0, period, kLinkRadius * dp);
      std::uint32_t count = 0;
      for (std::uint32_t i = 0; i < cand.size(); ++i) {
        bool crowded = false;
        bins.near(cand[i].p, radius, [&](std::uint32_t, glm::dvec3) { crowded = true; });
        if (crowded || !clear(cand[i])) continue;
        bins.add(cand[i].p, i);
        ++count;
        if (kept) kept->push_back(i);
      }
      return count;
    };
    // Bisection on the exclusion radius (the count falls as it grows), to within 0.2%.
    double lo = 0.75 * dp, hi = 1.35 * dp, best = 1.0 * dp, bestMiss = std::numeric_limits<double>::infinity();
    for (int it = 0; it < 16; ++it) {
      const double r = 0.5 * (lo + hi);
      const double count = sample(r, nullptr);
      const double miss = std::abs(count - target);
      if (miss < bestMiss) bestMiss = miss, best = r;
      if (miss <= std::max(0.5, 2e-3 * target)) break;
      if (count > target) lo = r;
      else hi = r;
    }
    std::vector<std::uint32_t> kept;
    sample(best, &kept);
    std::vector<glm::dvec3> layerPos, layerNormal;
    for (std::uint32_t i : kept) layerPos.push_back(cand[i].p), layerNormal.push_back(cand[i].n);
    relaxOnSurface(layerPos, layerNormal, q, T, N, best, [&](glm::dvec3 p) {
      return !(m.distance(p, offset) < kLayerClearance * offset) && !m.inside(p);
    }, wrap, Bins(binX0, period, kLinkRadius * dp), kLinkRadius * dp);
    for (std::size_t i = 0; i < layerPos.size(); ++i) {
      const auto id = std::uint32_t(pos.size());
      wallBins.add(layerPos[i], id);
      pos.push_back(layerPos[i]);
      inward.push_back(-layerNormal[i]);
      b.layer.push_back(std::uint8_t(l));
    }
  }
  b.wall = std::uint32_t(pos.size());

  // Springs between wall points nearer than kLinkRadius dp; the uniform widening's g.
  sim::SpringNetwork& net = b.network;
  std::vector<std::vector<std::uint32_t>> adjacent(b.wall);
  for (std::uint32_t i = 0; i < b.wall; ++i) {
    std::vector<std::pair<std::uint32_t, glm::dvec3>> near;
    wallBins.near(pos[i], kLinkRadius * dp, [&](std::uint32_t j, glm::dvec3 d) {
      if (j > i) near.emplace_back(j, d);
    });
    std::sort(near.begin(), near.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
    for (const auto& [j, d] : near) {
      const double length = glm::length(d);
      float k = t.stiffness, maxForce = t.maxForce;  // (the damping stays, as on the analytic sac)
      const glm::dvec3 mid = pos[i] + 0.5 * d;
      for (const AneurysmSpec::Region& r : spec.regions) {
        glm::dvec3 off = mid - r.centre;
        if (t.periodic) off.x -= L * std::round(off.x / L);
        if (glm::length(off) < r.radius) {
          k *= r.stiffnessScale;
          maxForce *= r.strengthScale;
          break;
        }
      }
      linkSpring(net, adjacent, {i, j, float(length), k, t.damping, maxForce});
      const double g = glm::dot(d / length, inward[i] - inward[j]);  // outward normals' difference, j minus i
      b.sumG2 += g * g;
      b.maxG = std::max(b.maxG, g);
    }
  }
  net.points.resize(b.wall);
  for (std::uint32_t i = 0; i < b.wall; ++i) {
    sim::WallPoint& w = net.points[i];
    w.mass = t.pointMass;
    if (spec.openEnds) {
      for (const MeshEnd& e : m.ends()) {
        // (within a spacing of the end's cap, on the end's side of the vessel)
        const glm::dvec3 d = pos[i] - e.centroid;
        const double s = -glm::dot(d, e.normal);
        if (s < dp && glm::length(d + s * e.normal) < e.radius + (t.layers + 1.0) * dp) w.anchored = true;
      }
    }
    double bestScore = 0.5;  // at least sin(30 deg) along the normal, else the point keeps its built normal
    for (std::uint32_t pa : adjacent[i])
      for (std::uint32_t pb : adjacent[i]) {
        if (pa == pb || b.layer[pa] != b.layer[i] || b.layer[pb] != b.layer[i]) continue;
        const glm::dvec3 ea = wallBins.separation(pos[i], pos[pa]), eb = wallBins.separation(pos[i], pos[pb]);
        const double score = glm::dot(glm::cross(ea, eb), inward[i]) / (glm::length(ea) * glm::length(eb));
        if (score > bestScore) bestScore = score, w.frameA = pa, w.frameB = pb;
      }
  }

  // Fluid: the dp lattice inside the lumen, row by row along x (one ray per row).
  ParticleSet& set = b.particles;
  for (std::uint32_t i = 0; i < b.wall; ++i) set.add(glm::vec3(pos[i]), t.fluidMass, float(HEMO_KIND_WALL), glm::vec3(inward[i]));
  const glm::dvec3 origin(x0, t.centreYZ.x, t.centreYZ.y);
  auto first = [&](int a) { return long(std::floor((m.min()[a] - origin[a]) / dp)); };
  auto last = [&](int a) { return long(std::ceil((m.max()[a] - origin[a]) / dp)); };
  const long ix0 = t.periodic ? 0 : first(0), ix1 = t.periodic ? std::lround(L / dp) - 1 : last(0);
  std::uint32_t fluid = 0;
  for (long j = first(1); j <= last(1); ++j)
    for (long k = first(2); k <= last(2); ++k) {
      const double y = origin.y + (j + 0.5) * dp, z = origin.z + (k + 0.5) * dp;
      const auto crossings = m.crossings(y, z);
      if (crossings.empty()) continue;
      for (long i = ix0; i <= ix1; ++i) {
        const glm::dvec3 p(origin.x + (i + 0.5) * dp, y, z);
        int count = 0;  // as VesselMesh::inside, with the row's crossings found once
        for (const auto& [x, sign] : crossings) count += x > p.x ? sign : 0;
        if (count == 0) continue;
        bool crowded = false;
        wallBins.near(p, kFluidClearance * dp, [&](std::uint32_t, glm::dvec3) { crowded = true; });
        if (crowded) continue;
        set.add(glm::vec3(p), t.fluidMass, float(HEMO_KIND_FLUID));
        ++fluid;
      }
    }
  set.fluid = fluid;
  set.boundary = 0;
  set.numberIds();
  net.validate();
  return b;
}

TissueSprings springsFromMeshTissue(const VesselMesh& mesh, const MeshVesselBuild& build, double E, double nu, double thickness,
                                    double sigmaF) {
  auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  if (!positive(E) || !positive(thickness) || !positive(sigmaF)) {
    throw std::invalid_argument("tissue: Young's modulus, wall thickness and failure stress must be positive");
  }
  if (!(std::isfinite(nu) && nu >= 0.0 && nu < 0.5)) throw std::invalid_argument("tissue: Poisson's ratio must be in [0, 0.5)");
  if (!(build.sumG2 > 0.0) || !(build.maxG > 0.0)) throw std::invalid_argument("mesh vessel: no spring stretches when the wall widens");
  const double A = mesh.area(), Re = 2.0 * mesh.volume() / mesh.area();
  TissueSprings out;
  out.stiffness = float(E * thickness * A / ((1.0 - nu * nu) * Re * Re * build.sumG2));
  out.maxForce = float(sigmaF * thickness * A * build.maxG / (Re * build.sumG2));
  return out;
}

io::TriangleMesh vesselSurface(const VesselSurfaceSpec& v) {
  auto positive = [](double x) { return std::isfinite(x) && x > 0.0; };
  if (!positive(v.length)) throw std::invalid_argument("length must be positive");
  if (!positive(v.radius)) throw std::invalid_argument("radius must be positive");
  if (!std::isfinite(v.bendHeight) || v.bendHeight < 0.0) throw std::invalid_argument("bend height must be zero or positive");
  if (v.sacRadius != 0.0 && !(positive(v.sacRadius) && v.sacRadius < 0.25 * v.length)) {
    throw std::invalid_argument("sac radius must be positive and under a quarter of the length");
  }
  if (v.sacRadius > 0.0 && !(std::isfinite(v.sacOffset) && v.sacOffset > v.radius && v.sacOffset < v.radius + v.sacRadius)) {
    throw std::invalid_argument("sac offset must lie between the radius and the radius plus the sac's (the sac must join the tube)");
  }
  if (v.around < 8 || v.around > 4096) throw std::invalid_argument("around must be 8 to 4096");
  if (!std::isfinite(v.straight) || v.straight < 0.0) throw std::invalid_argument("straight length must be zero or positive");
  const double pi = std::numbers::pi, L = v.length, S = v.straight, total = L + 2.0 * S;
  // The bend must not fold the tube onto itself: the axis' curvature radius stays above R.
  const double curvature = v.bendHeight * 2.0 * pi * pi / (L * L);
  if (curvature * v.radius >= 0.5) throw std::invalid_argument("bend height too large for the radius and length (the tube would fold)");
  const double phi = 2.0 * pi / v.around;
  const double R = v.radius * std::sqrt(phi / std::sin(phi));
  const std::uint32_t along = v.along > 0 ? v.along : std::max<std::uint32_t>(4, std::uint32_t(std::lround(total / (R * phi))));
  if (along > 100000) throw std::invalid_argument("along must be at most 100000");
  const glm::dvec3 sac(S + 0.5 * L, 0.0, v.bendHeight + v.sacOffset);  // relative to the start
  io::TriangleMesh m;
  for (std::uint32_t i = 0; i < along; ++i) {
    const double x = total * double(i) / along;
    const double xb = std::clamp(x - S, 0.0, L);  // along the bend (the straight runs: its ends)
    const double zc = 0.5 * v.bendHeight * (1.0 - std::cos(2.0 * pi * xb / L));
    const double slope = x - S > 0.0 && x - S < L ? v.bendHeight * pi / L * std::sin(2.0 * pi * xb / L) : 0.0;
    const double n = std::sqrt(1.0 + slope * slope);
    const glm::dvec3 e1(0.0, 1.0, 0.0), e2(-slope / n, 0.0, 1.0 / n);
    for (std::uint32_t j = 0; j < v.around; ++j) {
      const double theta = phi * j;
      double rho = R;
      if (v.sacRadius > 0.0) {  // the far side of the sac along the ray, where the ray meets it
        const glm::dvec3 u = std::cos(theta) * e1 + std::sin(theta) * e2, q = sac - glm::dvec3(x, 0.0, zc);
        const double b = glm::dot(u, q), disc = b * b - glm::dot(q, q) + v.sacRadius * v.sacRadius;
        if (disc > 0.0) rho = std::max(rho, b + std::sqrt(disc));
      }
      m.vertices.push_back(v.start + glm::dvec3(x, 0.0, zc) + rho * (std::cos(theta) * e1 + std::sin(theta) * e2));
    }
  }
  for (std::uint32_t j = 0; j < v.around; ++j) m.vertices.push_back(m.vertices[j] + glm::dvec3(total, 0.0, 0.0));
  auto id = [&](std::uint32_t i, std::uint32_t j) { return i * v.around + j % v.around; };
  for (std::uint32_t i = 0; i < along; ++i)
    for (std::uint32_t j = 0; j < v.around; ++j) {
      const std::uint32_t a = id(i, j), b = id(i, j + 1), c = id(i + 1, j + 1), d = id(i + 1, j);
      m.triangles.push_back({a, b, c});
      m.triangles.push_back({a, c, d});
    }
  return m;
}

}  // namespace hemo::scene
