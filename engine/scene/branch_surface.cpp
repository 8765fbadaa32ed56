// A branching vessel's surface by marching cubes over the signed distance to a union of
// capsules (hemo/scene/mesh_vessel.hpp, branchSurface).
#include "hemo/reference/marching_cubes.hpp"
#include "hemo/scene/mesh_vessel.hpp"
#include "hemo/surface/case_table.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <unordered_map>

namespace hemo::scene {
namespace {

struct Capsule {
  glm::dvec3 a, b;
  double radius;
};

// Signed distance from p to a capsule's surface (negative inside).
double capsuleDistance(const Capsule& c, glm::dvec3 p) {
  const glm::dvec3 ab = c.b - c.a;
  const double length2 = glm::dot(ab, ab);
  const double t = length2 > 0.0 ? std::clamp(glm::dot(p - c.a, ab) / length2, 0.0, 1.0) : 0.0;  // (a sphere: a = b)
  return glm::length(p - (c.a + t * ab)) - c.radius;
}

}  // namespace

io::TriangleMesh branchSurface(const BranchSurfaceSpec& s) {
  auto require = [](bool ok, const std::string& what) {
    if (!ok) throw std::invalid_argument("branch surface: " + what);
  };
  for (int a = 0; a < 3; ++a) require(std::isfinite(s.start[a]), "the start must be finite");
  require(std::isfinite(s.radius) && s.radius > 0.0, "the radius must be positive");
  require(std::isfinite(s.branchRadius) && s.branchRadius > 0.0 && s.branchRadius <= s.radius,
          "the branches' radius must be positive and at most the parent's");
  require(std::isfinite(s.angle) && s.angle > 0.0 && s.angle <= 80.0 * std::numbers::pi / 180.0,
          "the branch angle must lie in (0, 80] degrees");
  require(std::isfinite(s.spread) && s.spread > s.branchRadius, "the spread must exceed the branches' radius (they would touch)");
  const double cell = s.cell > 0.0 ? s.cell : s.branchRadius / 8.0;
  require(std::isfinite(cell) && cell <= 0.5 * s.branchRadius, "the cell must be positive and at most half the branches' radius");
  require(std::isfinite(s.split) && s.split >= 2.0 * s.radius, "the split must lie at least two radii from the inlet");
  const double bend = s.split + s.spread / std::tan(s.angle);  // x - x0 where the daughters turn parallel
  require(std::isfinite(s.length) && s.length >= bend + 2.0 * s.branchRadius,
          "the length must reach at least two branch radii past the bends (at " + std::to_string(bend) + " m from the inlet)");
  require(std::isfinite(s.sacRadius) && s.sacRadius >= 0.0, "the sac's radius must be zero (none) or positive");
  if (s.sacRadius > 0.0) {
    const double apex = s.branchRadius / std::sin(s.angle);
    require(std::isfinite(s.sacOffset) && s.sacOffset > 0.0 && s.sacOffset - s.sacRadius < apex,
            "the sac must lie past the split and reach the apex between the daughters (its offset less its radius under " +
                std::to_string(apex) + " m)");
    require(s.split + s.sacOffset + s.sacRadius < s.length - 2.0 * s.branchRadius, "the sac must end two branch radii before the outlets");
    require(s.sacRadius < s.spread, "the sac's radius must be under the spread");
  }
  // The capsules: the parent, and per daughter its oblique leg and its straight run; the
  // parent and the runs reach two cells past the grid's end planes, so the surface meets them
  // as plain cylinders.
  const glm::dvec3 o = s.start, splitPoint = o + glm::dvec3(s.split, 0.0, 0.0);
  std::vector<Capsule> caps{{o - glm::dvec3(2.0 * cell, 0.0, 0.0), splitPoint, s.radius}};
  for (const double side : {1.0, -1.0}) {
    const glm::dvec3 turn = o + glm::dvec3(bend, side * s.spread, 0.0);
    caps.push_back({splitPoint, turn, s.branchRadius});
    caps.push_back({turn, o + glm::dvec3(s.length + 2.0 * cell, side * s.spread, 0.0), s.branchRadius});
  }
  if (s.sacRadius > 0.0) {
    const glm::dvec3 centre = splitPoint + glm::dvec3(s.sacOffset, 0.0, 0.0);
    caps.push_back({centre, centre, s.sacRadius});
  }
  // The grid: x from x0 to x0 + length exactly, y and z past the lumen by three cells; in y an
  // even number of points, symmetric about the parent's axis (the two daughters' surfaces are
  // mirror images), none on it; in z off the axis by a fraction of a cell.
  reference::ScalarGrid grid;
  const auto nx = std::uint32_t(std::max(2.0, std::round(s.length / cell)));
  grid.spacing = s.length / double(nx);
  const double h = grid.spacing;
  const double yHalf = s.spread + s.branchRadius + 3.0 * h, zHalf = std::max(s.radius, s.sacRadius) + 3.0 * h;
  const auto ny = 2 * std::uint32_t(std::ceil(yHalf / h)), nz = std::uint32_t(std::ceil(2.0 * zHalf / h)) + 1;
  const std::size_t points = std::size_t(nx + 1) * ny * nz;
  require(points <= 64u * 1024u * 1024u, "the grid of " + std::to_string(points) + " points is too fine (raise the cell)");
  grid.points = glm::uvec3(nx + 1, ny, nz);
  grid.origin = o - glm::dvec3(0.0, 0.5 * double(ny - 1) * h, 0.5 * double(nz - 1) * h + 0.291 * h);
  grid.values.resize(points);
  const double floorValue = 0.02 * h;
  for (std::uint32_t k = 0; k < nz; ++k) {
    for (std::uint32_t j = 0; j < ny; ++j) {
      for (std::uint32_t i = 0; i <= nx; ++i) {
        const glm::dvec3 p = grid.origin + h * glm::dvec3(i, j, k);
        double d = 1e300;
        for (const Capsule& c : caps) d = std::min(d, capsuleDistance(c, p));
        double f = -d;  // (inside: above the iso level)
        if (std::abs(f) < floorValue) f = f < 0.0 ? -floorValue : floorValue;
        grid.values[grid.index(i, j, k)] = f;
      }
    }
  }
  const reference::RefMesh soup = reference::marchingCubes(grid, 0.0, surface::buildCaseTable());
  io::TriangleMesh mesh;
  std::unordered_map<std::uint64_t, std::uint32_t> byEdge;
  for (std::size_t t = 0; t < soup.triangleCount(); ++t) {
    std::array<std::uint32_t, 3> tri{};
    for (int c = 0; c < 3; ++c) {
      const std::size_t v = 3 * t + std::size_t(c);
      const auto [it, added] = byEdge.emplace(soup.edgeKeys[v], std::uint32_t(mesh.vertices.size()));
      if (added) mesh.vertices.push_back(soup.positions[v]);
      tri[std::size_t(c)] = it->second;
    }
    mesh.triangles.push_back(tri);
  }
  return mesh;
}

}  // namespace hemo::scene
