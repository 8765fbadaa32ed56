#pragma once
// CPU double-precision twin of the GPU surface stages (compute_shaders/mc/): the particle
// field and marching cubes over it, in the same order and with the same conventions
// (hemo/surface/case_table.hpp), so the GPU mesh can be compared triangle by triangle.
#include "hemo/surface/case_table.hpp"

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <cstdint>
#include <vector>

namespace hemo::reference {

// A scalar field sampled at the points of a uniform grid, x fastest: value (i, j, k) is at
// origin + spacing (i, j, k).
struct ScalarGrid {
  glm::dvec3 origin{0.0};  // m
  double spacing = 0.0;    // m
  glm::uvec3 points{0u};   // points per axis (voxels per axis = points - 1)
  std::vector<double> values;

  std::size_t index(std::uint32_t i, std::uint32_t j, std::uint32_t k) const {
    return i + std::size_t(points.x) * (j + std::size_t(points.y) * k);
  }
  double at(std::uint32_t i, std::uint32_t j, std::uint32_t k) const { return values[index(i, j, k)]; }
};

// Triangles as vertex triples (positions[3t .. 3t+2]), wound counter-clockwise seen from the
// outside (the side where the field is below the iso level).
struct RefMesh {
  std::vector<glm::dvec3> positions;  // m
  std::vector<glm::dvec3> normals;    // unit: minus the interpolated field gradient; the
                                      // triangle's own normal where the gradient vanishes
  std::vector<std::uint64_t> edgeKeys;  // the grid edge under each vertex: 3 * point + axis
  std::vector<std::uint8_t> cases;      // the case of the voxel each triangle came from
  std::size_t triangleCount() const { return positions.size() / 3; }
};

// Marching cubes (Lorensen & Cline 1987) with hemo's case table. A point is inside when its
// value is greater than `iso`. Voxels are visited x fastest; each vertex is interpolated
// linearly along its grid edge from the lower to the upper point. The gradient at grid points
// is the central difference (one-sided on the grid's faces).
RefMesh marchingCubes(const ScalarGrid& grid, double iso, const surface::CaseTable& table);

double meshArea(const RefMesh& mesh);  // m^2
// Enclosed volume by the divergence theorem (m^3); meaningful for a closed mesh.
double meshVolume(const RefMesh& mesh);

// The particle field hemo extracts the blood surface from: the SPH estimate of the fluid's
// volume fraction, phi(x) = sum_j (m_j / rho_j) W(|x - x_j|, h) with the Wendland C2 kernel
// (1 inside the fluid, 0 far from it, about 1/2 at the free surface). `particles` are xyz in
// m with the mass (kg) in w; `densities` in kg/m^3 (one per particle).
double particleField(const glm::dvec3& x, const std::vector<glm::dvec4>& particles, const std::vector<double>& densities,
                     double h);

}  // namespace hemo::reference
