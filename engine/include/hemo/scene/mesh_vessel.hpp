#pragma once
// A vessel from a triangle surface: the lumen as segmented from CT or MR angiography and
// exported as STL or OBJ (hemo/io/mesh.hpp). The surface is the lumen's boundary, its
// triangles wound counter-clockwise seen from outside (outward normals); it is open where
// the vessel is cut off (inlets and outlets: its boundary loops).
//
// VesselMesh checks the surface and answers the builder's questions: inside the lumen or not
// (the surface closed by flat caps over its loops; the sign of the crossings along a ray),
// how far from the surface, and where its ends are. buildMeshVessel turns it into particles
// as the analytic vessels do: wall points in layers at (l + 1/2) dp outside the surface,
// joined by springs, and the fluid on the dp lattice inside.
#include "hemo/io/mesh.hpp"
#include "hemo/scene/tube.hpp"
#include "hemo/sim/wall.hpp"

#include <glm/vec3.hpp>

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace hemo::scene {

struct AneurysmSpec;

// An open boundary loop of the surface: where the vessel is cut off.
struct MeshEnd {
  std::vector<std::uint32_t> loop;  // vertex indices, in the order of the surface's boundary edges
  glm::dvec3 centroid{0.0};         // m, of the flat cap that closes it
  glm::dvec3 normal{0.0};           // out of the lumen, through the cap
  double area = 0.0;                // m^2, of the cap
  double radius = 0.0;              // m, sqrt(area / pi)
};

class VesselMesh {
 public:
  // `mesh` in metres. Throws std::invalid_argument naming the problem and where it is: fewer
  // than 4 triangles, a zero-area triangle, an edge shared by more than two triangles (non-
  // manifold), two triangles that run a shared edge the same way (inconsistent winding), a
  // vertex where two boundary loops touch, separate pieces, and a surface whose closed volume
  // is negative (normals pointing into the lumen).
  explicit VesselMesh(io::TriangleMesh mesh);

  const io::TriangleMesh& surface() const { return mesh_; }
  const std::vector<MeshEnd>& ends() const { return ends_; }
  // Unit outward normal at each vertex (angle-weighted over its triangles).
  const std::vector<glm::dvec3>& vertexNormals() const { return normals_; }
  glm::dvec3 min() const { return min_; }
  glm::dvec3 max() const { return max_; }
  double area() const { return area_; }      // m^2, the surface's (caps excluded)
  double volume() const { return volume_; }  // m^3, of the lumen closed by the caps

  // Whether p lies inside the lumen closed by flat caps over the ends: the signed count of
  // the closed surface's crossings along the ray from p towards +x is not zero. Exact
  // tie-breaking on shared edges counts a ray through an edge or vertex once.
  bool inside(glm::dvec3 p) const;
  // The signed crossings of the closed surface by the line through (y, z) along x, sorted by
  // x: +1 where it leaves the lumen going +x, -1 where it enters (inside: the sum beyond x is
  // not zero).
  std::vector<std::pair<double, int>> crossings(double y, double z) const;
  // Distance from p to the surface (caps excluded), or `within` if it is farther than that.
  double distance(glm::dvec3 p, double within) const;

  // The closed surface's column and cell grids (built once; copies share them, read only).
  struct Index;

 private:
  io::TriangleMesh mesh_;
  std::vector<MeshEnd> ends_;
  std::vector<glm::dvec3> normals_;
  glm::dvec3 min_{0.0}, max_{0.0};
  double area_ = 0.0, volume_ = 0.0;
  std::shared_ptr<const Index> index_;
};

struct MeshVesselBuild {
  ParticleSet particles;  // wall particles first (ids 0 .. wall-1), then the fluid
  sim::SpringNetwork network;
  std::uint32_t wall = 0;
  std::vector<std::uint8_t> layer;  // per wall point
  // The uniform widening's geometry, for the tissue mapping (springsFromMeshTissue): with
  // every wall point moved by u along its outward normal, spring s stretches by g_s u.
  double sumG2 = 0.0;  // sum over springs of g_s^2 (1)
  double maxG = 0.0;   // the largest g_s
};

// Builds the vessel of `spec.mesh` with the tube's wall parameters in spec.tube (spacing,
// layers, point mass, spring stiffness, damping and maximum force, fluid mass; periodic along
// x from x0 over `length` when spec.tube.periodic, and then every end must lie on one of the
// two planes and match its partner on the other). Each wall layer l is the surface moved out
// by (l + 1/2) dp along its vertex normals, sampled greedily from candidates a quarter
// spacing apart in a fixed pseudo-random order, with an exclusion distance chosen by
// bisection so that every layer holds one point per dp^2 of the lumen's area (as the tube's
// rings), then evened out by rounds of repulsion on the moved surface (the greedy sample's
// holes are as wide as its exclusion distance): the same mesh always gives the same points.
// Springs join wall points nearer than 1.75 dp (within and across layers), with the wall's
// stiffness and strength scaled where their midpoint lies in one of spec.regions; each point's frame
// takes the pair of same-layer neighbours that best spans the surface. The fluid fills the dp
// lattice (aligned with x0 and the inlet's centre) inside the lumen. Throws
// std::invalid_argument naming the problem. docs/meshes.md.
MeshVesselBuild buildMeshVessel(const AneurysmSpec& spec);

// Springs from tissue properties for a mesh vessel, as springsFromTissue does for a tube:
// the stiffness and maximum force with which the built layout, widened uniformly, has the
// hoop response of a thin tube of Young's modulus E, Poisson ratio nu, thickness t and
// failure stress sigma_f whose radius is Re = 2 V / A (the lumen's volume over its area: the
// radius, for a straight tube):
//   k = E t A / ((1 - nu^2) Re^2 sum g^2),   f_max = sigma_f t A g_max / (Re sum g^2).
TissueSprings springsFromMeshTissue(const VesselMesh& mesh, const MeshVesselBuild& build, double youngsModulus,
                                    double poissonRatio, double thickness, double failureStress);

// The project's own vessel surfaces (hemo-mesh writes them as STL): a tube of radius R along
// x over one period L whose axis rises and falls, z(x) = H (1 - cos(2 pi x / L)) / 2 (a
// straight tube when H = 0), with an optional saccular aneurysm on the outer side of the
// crest: a sphere of radius Rs whose centre lies `sacOffset` above the axis at x = L/2. The
// surface is a grid of `around` x `along` quads (each split in two, wound counter-clockwise
// seen from outside) on rays from the axis across it, each ray ending at the tube or at the
// far side of the sphere where it meets the sphere: the tube and sac as seen from the axis
// (where the sac overhangs its neck, the neck widens to the sac's shadow). The rings' corners
// sit at R sqrt(phi / sin(phi)) (phi = 2 pi / around) so each ring's polygon has the
// circle's area. A straight run of length S (0: none) may lead into the bend and out of it
// (the bend and the sac then start S along: open ends want a straight run for their buffers).
// The ends are open and lie in the planes x = x0 and x0 + L + 2 S, the last ring a copy of
// the first shifted by L + 2 S (a periodic vessel's ends match exactly).
struct VesselSurfaceSpec {
  glm::dvec3 start{0.0};      // m, the axis at x = x0
  double length = 0.0;        // m, L
  double radius = 0.0;        // m, R
  double bendHeight = 0.0;    // m, H
  double sacRadius = 0.0;     // m, Rs (0: no sac)
  double sacOffset = 0.0;     // m, from the axis to the sac's centre (R < offset < R + Rs)
  std::uint32_t around = 64;  // quads around
  std::uint32_t along = 0;    // quads along (0: about square quads)
  double straight = 0.0;      // m, S: a straight run of the tube before the bend and after it
};
// Throws std::invalid_argument naming the parameter.
io::TriangleMesh vesselSurface(const VesselSurfaceSpec& spec);

// A branching vessel (hemo-mesh --branch-angle-deg): a parent tube of radius R along +x from
// `start` splits `split` along into two daughters of radius Rb, whose axes leave the parent's
// at +-angle in the x-y plane until they lie `spread` off it, then run parallel to x to the
// ends at x0 + length (straight, for open ends' buffers). The lumen is the union of capsules
// (cylinders with spherical ends) of those radii about the axes; the surface is marching
// cubes (hemo's case table, reference::marchingCubes) over its signed distance, sampled on a
// grid of about `cell` whose first and last planes are the ends' x = x0 and x0 + length, so
// the surface is open there: three boundary loops, the inlet at x0 and the two outlets at
// (x0 + length, y0 +- spread, z0). An optional saccular aneurysm at the apex: a sphere of
// radius Rs centred `sacOffset` past the split along x (between the daughters, where the
// parent's flow meets the carina; it must reach the apex, Rb / sin(angle) past the split). Grid values within 2% of a cell of the surface are moved
// out to that distance, so no vertex lands on a grid point (no zero-area triangle). The
// vertices are shared through their grid edges.
struct BranchSurfaceSpec {
  glm::dvec3 start{0.0};      // m, the parent's axis at x = x0
  double length = 0.0;        // m, from the inlet's plane to the outlets'
  double radius = 0.0;        // m, R
  double branchRadius = 0.0;  // m, Rb (<= R)
  double angle = 0.0;         // rad, each daughter's to the parent's axis (0, 80 degrees]
  double split = 0.0;         // m along x from x0 to the split
  double spread = 0.0;        // m, each daughter's straight run off the parent's axis (> Rb)
  double cell = 0.0;          // m, the grid's spacing (0: Rb / 8)
  double sacRadius = 0.0;     // m, Rs (0: no sac)
  double sacOffset = 0.0;     // m, from the split to the sac's centre along x
};
// Throws std::invalid_argument naming the parameter.
io::TriangleMesh branchSurface(const BranchSurfaceSpec& spec);

}  // namespace hemo::scene
