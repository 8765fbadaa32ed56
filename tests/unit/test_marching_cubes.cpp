// The marching-cubes case table (derived by hemo's own code) and the CPU reference mesher:
// every case a consistent patch, closed meshes from closed fields, and the area and volume of
// analytic surfaces converging to the exact values.
#include "hemo/reference/marching_cubes.hpp"
#include "hemo/surface/case_table.hpp"

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include <cmath>
#include <functional>
#include <map>
#include <numbers>
#include <random>
#include <set>
#include <utility>

namespace {

using hemo::reference::ScalarGrid;
using hemo::surface::CaseTable;

bool inside(int cube, int corner) { return ((cube >> corner) & 1) != 0; }

// Faces of the cube as the sets of their four corners (axis, side).
std::set<int> faceCorners(int axis, int side) {
  std::set<int> corners;
  for (int c = 0; c < 8; ++c) {
    if (((c >> axis) & 1) == side) corners.insert(c);
  }
  return corners;
}

// The face both cube edges lie on (-1 if none): encoded 2 axis + side.
int commonFace(int e1, int e2) {
  const auto& edges = hemo::surface::cubeEdges();
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      const std::set<int> f = faceCorners(axis, side);
      if (f.count(edges[e1].a) && f.count(edges[e1].b) && f.count(edges[e2].a) && f.count(edges[e2].b)) {
        return 2 * axis + side;
      }
    }
  }
  return -1;
}

TEST(McTable, EveryCaseIsAConsistentPatch) {
  const CaseTable table = hemo::surface::buildCaseTable();
  const auto& edges = hemo::surface::cubeEdges();
  EXPECT_EQ(table.triangleCount[0], 0);
  EXPECT_EQ(table.triangleCount[255], 0);
  EXPECT_LE(table.maxTriangles, hemo::surface::kMaxTrianglesPerCube);
  for (int cube = 0; cube < 256; ++cube) {
    SCOPED_TRACE("case " + std::to_string(cube));
    // (a) Vertices lie exactly on the edges whose corners differ in sign, and on all of them.
    std::set<int> crossing, used;
    for (int e = 0; e < 12; ++e) {
      if (inside(cube, edges[e].a) != inside(cube, edges[e].b)) crossing.insert(e);
    }
    std::map<std::pair<int, int>, int> directed;
    for (int t = 0; t < table.triangleCount[cube]; ++t) {
      const auto* v = &table.edges[cube][3 * t];
      ASSERT_NE(v[0], v[1]);
      ASSERT_NE(v[1], v[2]);
      ASSERT_NE(v[0], v[2]);
      for (int k = 0; k < 3; ++k) {
        used.insert(v[k]);
        ++directed[{v[k], v[(k + 1) % 3]}];
      }
    }
    EXPECT_EQ(used, crossing);
    // (b) Inner edges are shared by two triangles with opposite directions; the others are
    // the patch's boundary and lie on a face of the cube.
    std::map<int, std::vector<std::pair<int, int>>> boundaryByFace;
    for (const auto& [edge, count] : directed) {
      EXPECT_EQ(count, 1) << "edge " << edge.first << "-" << edge.second << " used twice in one direction";
      if (directed.count({edge.second, edge.first})) {
        EXPECT_EQ(commonFace(edge.first, edge.second), -1)
            << "inner edge " << edge.first << "-" << edge.second << " lies in a cube face";
        continue;
      }
      const int face = commonFace(edge.first, edge.second);
      ASSERT_GE(face, 0) << "boundary edge " << edge.first << "-" << edge.second << " is not on a cube face";
      boundaryByFace[face].push_back(edge);
    }
    // (c) On each face the boundary is the contour the face's own signs imply: one segment for
    // two sign changes; for four (inside corners on a diagonal) two segments, each cutting off
    // an inside corner. Neighbouring cubes then agree on their shared face.
    for (int axis = 0; axis < 3; ++axis) {
      for (int side = 0; side < 2; ++side) {
        const std::set<int> f = faceCorners(axis, side);
        int changes = 0;
        for (int e : crossing) {
          if (f.count(edges[e].a) && f.count(edges[e].b)) ++changes;
        }
        const auto& segments = boundaryByFace[2 * axis + side];
        ASSERT_EQ(int(segments.size()), changes / 2) << "face " << axis << "/" << side;
        if (changes == 4) {
          for (const auto& [e1, e2] : segments) {
            int shared = -1;
            for (int c : {int(edges[e1].a), int(edges[e1].b)}) {
              if (c == edges[e2].a || c == edges[e2].b) shared = c;
            }
            ASSERT_GE(shared, 0);
            EXPECT_TRUE(inside(cube, shared)) << "an ambiguous face must cut off its inside corners";
          }
        }
      }
    }
  }
}

TEST(McTable, PackingRoundTrips) {
  const CaseTable table = hemo::surface::buildCaseTable();
  const auto packed = hemo::surface::packCaseTable(table);
  ASSERT_EQ(packed.size(), 1024u);
  for (int cube = 0; cube < 256; ++cube) {
    ASSERT_EQ(packed[4 * cube], table.triangleCount[cube]);
    for (int k = 0; k < 3 * table.triangleCount[cube]; ++k) {
      EXPECT_EQ((packed[4 * cube + 1 + k / 8] >> (4 * (k % 8))) & 15u, table.edges[cube][k]);
    }
  }
}

ScalarGrid sampleGrid(glm::dvec3 lo, double spacing, glm::uvec3 points, const std::function<double(glm::dvec3)>& f) {
  ScalarGrid g;
  g.origin = lo;
  g.spacing = spacing;
  g.points = points;
  g.values.resize(std::size_t(points.x) * points.y * points.z);
  for (std::uint32_t k = 0; k < points.z; ++k) {
    for (std::uint32_t j = 0; j < points.y; ++j) {
      for (std::uint32_t i = 0; i < points.x; ++i) g.values[g.index(i, j, k)] = f(lo + spacing * glm::dvec3(i, j, k));
    }
  }
  return g;
}

// Every grid edge carrying a vertex is shared by exactly two triangles, in opposite
// directions, and no triangle is degenerate.
void expectWatertight(const hemo::reference::RefMesh& mesh) {
  std::map<std::pair<std::uint64_t, std::uint64_t>, int> directed;
  for (std::size_t t = 0; t < mesh.triangleCount(); ++t) {
    const glm::dvec3* p = &mesh.positions[3 * t];
    ASSERT_GT(glm::length(glm::cross(p[1] - p[0], p[2] - p[0])), 0.0) << "triangle " << t;
    for (int k = 0; k < 3; ++k) ++directed[{mesh.edgeKeys[3 * t + k], mesh.edgeKeys[3 * t + (k + 1) % 3]}];
  }
  for (const auto& [edge, count] : directed) {
    ASSERT_EQ(count, 1) << "edge " << edge.first << " -> " << edge.second << " is used twice in the same direction";
    ASSERT_EQ(directed.count({edge.second, edge.first}), 1u) << "an edge has no opposite";
  }
}

TEST(McReference, RandomClosedFieldsGiveWatertightMeshesAndCoverEveryCase) {
  const CaseTable table = hemo::surface::buildCaseTable();
  std::set<int> seen;
  for (unsigned seed : {1u, 2u, 3u}) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const glm::uvec3 n(24, 22, 20);
    ScalarGrid g = sampleGrid(glm::dvec3(0.0), 0.1, n, [&](glm::dvec3) { return u(rng); });
    // Outside on the grid's faces, so the surface closes.
    for (std::uint32_t k = 0; k < n.z; ++k) {
      for (std::uint32_t j = 0; j < n.y; ++j) {
        for (std::uint32_t i = 0; i < n.x; ++i) {
          if (i == 0 || j == 0 || k == 0 || i + 1 == n.x || j + 1 == n.y || k + 1 == n.z) g.values[g.index(i, j, k)] = 0.0;
        }
      }
    }
    const auto mesh = hemo::reference::marchingCubes(g, 0.5, table);
    ASSERT_GT(mesh.triangleCount(), 1000u);
    expectWatertight(mesh);
    seen.insert(mesh.cases.begin(), mesh.cases.end());
    // Closed and outward-wound: a positive enclosed volume.
    EXPECT_GT(hemo::reference::meshVolume(mesh), 0.0);
  }
  EXPECT_EQ(seen.size(), 254u) << "every case with triangles appears";
}

struct Convergence {
  double areaError[3], volumeError[3];
};

// Relative area and volume errors of a closed analytic surface on grids of 32, 64 and 128
// points across its box.
Convergence measure(const std::function<double(glm::dvec3)>& f, glm::dvec3 halfBox, double area, double volume,
                    const std::function<void(const hemo::reference::RefMesh&)>& check = {}) {
  const CaseTable table = hemo::surface::buildCaseTable();
  Convergence c{};
  const std::uint32_t sizes[3] = {32, 64, 128};
  for (int s = 0; s < 3; ++s) {
    const double spacing = 2.0 * std::max({halfBox.x, halfBox.y, halfBox.z}) / (sizes[s] - 1);
    const glm::uvec3 points = glm::uvec3(glm::ceil(2.0 * halfBox / spacing)) + 1u;
    const auto mesh = hemo::reference::marchingCubes(sampleGrid(-halfBox, spacing, points, f), 0.0, table);
    if (check) check(mesh);
    c.areaError[s] = std::abs(hemo::reference::meshArea(mesh) / area - 1.0);
    c.volumeError[s] = std::abs(hemo::reference::meshVolume(mesh) / volume - 1.0);
  }
  return c;
}

// Within 1% at 128 points across, and the errors fall with every refinement.
void expectConverges(const char* name, const Convergence& conv) {
  for (int s = 0; s < 3; ++s) {
    std::printf("%s grid %d: area error %.4f%%, volume error %.4f%%\n", name, 32 << s, 100 * conv.areaError[s],
                100 * conv.volumeError[s]);
  }
  EXPECT_LT(conv.areaError[2], 0.01);
  EXPECT_LT(conv.volumeError[2], 0.01);
  for (int s = 1; s < 3; ++s) {
    EXPECT_LT(conv.areaError[s], conv.areaError[s - 1]) << name << " area, grid " << (32 << s);
    EXPECT_LT(conv.volumeError[s], conv.volumeError[s - 1]) << name << " volume, grid " << (32 << s);
  }
}

TEST(McReference, SphereAreaAndVolumeConverge) {
  const double R = 0.8e-3;  // m
  const auto conv = measure([R](glm::dvec3 x) { return R - glm::length(x); }, glm::dvec3(1.13 * R),
                            4.0 * std::numbers::pi * R * R, 4.0 / 3.0 * std::numbers::pi * R * R * R,
                            [](const hemo::reference::RefMesh& mesh) {
                              expectWatertight(mesh);
                              // Outward: every vertex normal and every winding points away from the centre.
                              for (std::size_t t = 0; t < mesh.triangleCount(); ++t) {
                                const glm::dvec3* p = &mesh.positions[3 * t];
                                const glm::dvec3 c = (p[0] + p[1] + p[2]) / 3.0;
                                ASSERT_GT(glm::dot(glm::cross(p[1] - p[0], p[2] - p[0]), c), 0.0);
                                for (int k = 0; k < 3; ++k) {
                                  ASSERT_GT(glm::dot(mesh.normals[3 * t + k], glm::normalize(p[k])), 0.99);
                                }
                              }
                            });
  expectConverges("sphere", conv);
}

// Surface area of the ellipsoid with semi-axes a >= b >= c (Legendre's formula with the
// incomplete elliptic integrals F and E).
double ellipsoidArea(double a, double b, double c) {
  const double phi = std::acos(c / a);
  const double k = std::sqrt(a * a * (b * b - c * c) / (b * b * (a * a - c * c)));
  const double s = std::sin(phi), co = std::cos(phi);
  return 2.0 * std::numbers::pi * c * c +
         2.0 * std::numbers::pi * a * b / s * (std::ellint_2(k, phi) * s * s + std::ellint_1(k, phi) * co * co);
}

TEST(McReference, EllipsoidAreaAndVolumeConverge) {
  const double a = 1.0e-3, b = 0.7e-3, c = 0.45e-3;
  // A field with a non-uniform gradient: 1 - the ellipsoidal radius.
  const auto f = [=](glm::dvec3 x) { return 1.0 - glm::length(x / glm::dvec3(a, b, c)); };
  // The formula against the closed form of an oblate spheroid (b -> a).
  const double oblate = ellipsoidArea(1.0, 1.0 - 1e-9, 0.5);
  const double e = std::sqrt(1.0 - 0.25);
  EXPECT_NEAR(oblate, 2 * std::numbers::pi * (1.0 + 0.25 / e * std::atanh(e)), 1e-6);
  const auto conv = measure(f, 1.12 * glm::dvec3(a, b, c), ellipsoidArea(a, b, c), 4.0 / 3.0 * std::numbers::pi * a * b * c,
                            expectWatertight);
  expectConverges("ellipsoid", conv);
}

TEST(McReference, ParticleFieldIsAVolumeFraction) {
  // A cubic lattice of particles with m / rho = dp^3: the field is close to 1 in the middle
  // (the Wendland kernel's lattice sum is 1 to within 1% at h = 1.3 dp) and 0 beyond 2h.
  const double dp = 1e-3, h = 1.3 * dp, rho = 1000.0;
  std::vector<glm::dvec4> particles;
  for (int k = 0; k < 10; ++k) {
    for (int j = 0; j < 10; ++j) {
      for (int i = 0; i < 10; ++i) particles.emplace_back((i + 0.5) * dp, (j + 0.5) * dp, (k + 0.5) * dp, rho * dp * dp * dp);
    }
  }
  const std::vector<double> densities(particles.size(), rho);
  EXPECT_NEAR(hemo::reference::particleField(glm::dvec3(5 * dp), particles, densities, h), 1.0, 0.01);
  EXPECT_EQ(hemo::reference::particleField(glm::dvec3(10 * dp + 2 * h + 1e-9), particles, densities, h), 0.0);
  const double face = hemo::reference::particleField(glm::dvec3(10 * dp, 5 * dp, 5 * dp), particles, densities, h);
  EXPECT_GT(face, 0.3);
  EXPECT_LT(face, 0.7);
}

}  // namespace
