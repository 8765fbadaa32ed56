#include "hemo/reference/marching_cubes.hpp"

#include "hemo/reference/sph.hpp"

#include <glm/geometric.hpp>

#include <cmath>

namespace hemo::reference {
namespace {

glm::dvec3 gradientAt(const ScalarGrid& g, std::uint32_t i, std::uint32_t j, std::uint32_t k) {
  const std::uint32_t idx[3] = {i, j, k};
  glm::dvec3 grad(0.0);
  for (int axis = 0; axis < 3; ++axis) {
    std::uint32_t lo[3] = {i, j, k}, hi[3] = {i, j, k};
    if (idx[axis] > 0) --lo[axis];
    if (idx[axis] + 1 < g.points[axis]) ++hi[axis];
    const double span = double(hi[axis] - lo[axis]) * g.spacing;
    if (span > 0.0) grad[axis] = (g.at(hi[0], hi[1], hi[2]) - g.at(lo[0], lo[1], lo[2])) / span;
  }
  return grad;
}

}  // namespace

RefMesh marchingCubes(const ScalarGrid& grid, double iso, const surface::CaseTable& table) {
  RefMesh mesh;
  if (grid.points.x < 2 || grid.points.y < 2 || grid.points.z < 2) return mesh;
  const auto& edges = surface::cubeEdges();
  for (std::uint32_t k = 0; k + 1 < grid.points.z; ++k) {
    for (std::uint32_t j = 0; j + 1 < grid.points.y; ++j) {
      for (std::uint32_t i = 0; i + 1 < grid.points.x; ++i) {
        int cube = 0;
        for (int c = 0; c < 8; ++c) {
          if (grid.at(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1)) > iso) cube |= 1 << c;
        }
        const int count = table.triangleCount[cube];
        for (int t = 0; t < count; ++t) {
          glm::dvec3 p[3], n[3];
          for (int v = 0; v < 3; ++v) {
            const surface::CubeEdge& e = edges[table.edges[cube][3 * t + v]];
            const std::uint32_t ai = i + (e.a & 1), aj = j + ((e.a >> 1) & 1), ak = k + ((e.a >> 2) & 1);
            const std::uint32_t bi = i + (e.b & 1), bj = j + ((e.b >> 1) & 1), bk = k + ((e.b >> 2) & 1);
            const double va = grid.at(ai, aj, ak), vb = grid.at(bi, bj, bk);
            const double s = (iso - va) / (vb - va);
            const glm::dvec3 pa = grid.origin + grid.spacing * glm::dvec3(ai, aj, ak);
            const glm::dvec3 pb = grid.origin + grid.spacing * glm::dvec3(bi, bj, bk);
            p[v] = pa + s * (pb - pa);
            n[v] = -(gradientAt(grid, ai, aj, ak) * (1.0 - s) + gradientAt(grid, bi, bj, bk) * s);
            mesh.edgeKeys.push_back(3 * std::uint64_t(grid.index(ai, aj, ak)) + e.axis);
          }
          const glm::dvec3 face = glm::cross(p[1] - p[0], p[2] - p[0]);
          const double faceLength = glm::length(face);
          for (int v = 0; v < 3; ++v) {
            const double len = glm::length(n[v]);
            if (len > 1e-30) {
              n[v] /= len;
            } else {
              n[v] = faceLength > 0.0 ? face / faceLength : glm::dvec3(0.0);
            }
            mesh.positions.push_back(p[v]);
            mesh.normals.push_back(n[v]);
          }
          mesh.cases.push_back(std::uint8_t(cube));
        }
      }
    }
  }
  return mesh;
}

double meshArea(const RefMesh& mesh) {
  double area = 0.0;
  for (std::size_t t = 0; t < mesh.triangleCount(); ++t) {
    const glm::dvec3* p = &mesh.positions[3 * t];
    area += 0.5 * glm::length(glm::cross(p[1] - p[0], p[2] - p[0]));
  }
  return area;
}

double meshVolume(const RefMesh& mesh) {
  double volume = 0.0;
  for (std::size_t t = 0; t < mesh.triangleCount(); ++t) {
    const glm::dvec3* p = &mesh.positions[3 * t];
    volume += glm::dot(p[0], glm::cross(p[1], p[2])) / 6.0;
  }
  return volume;
}

double particleField(const glm::dvec3& x, const std::vector<glm::dvec4>& particles, const std::vector<double>& densities,
                     double h) {
  double phi = 0.0;
  for (std::size_t j = 0; j < particles.size(); ++j) {
    const double r = glm::length(x - glm::dvec3(particles[j]));
    if (r < 2.0 * h) phi += particles[j].w / densities[j] * kernelW(r, h);
  }
  return phi;
}

}  // namespace hemo::reference
