#pragma once
// A straight vessel: a tube wall of wall particles on a cylindrical lattice (several layers),
// its spring network, and the fluid filling it. The tube's axis is parallel to x.
#include "hemo/scene/builders.hpp"
#include "hemo/sim/wall.hpp"

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <vector>

namespace hemo::scene {

struct TubeSpec {
  float x0 = 0.0f;                    // m, where the tube starts
  float length = 0.0f;                // m, along +x (a whole number of spacings if periodic)
  glm::vec2 centreYZ{0.0f};           // m, the axis
  float radius = 0.0f;                // m, inner radius: the fluid fills r < radius
  float spacing = 0.0f;               // m, particle spacing dp (fluid and wall)
  std::uint32_t layers = 2;           // wall layers at radii radius + (l + 1/2) dp
  float pointMass = 0.0f;             // kg, mass of each wall point (for the springs)
  float stiffness = 0.0f;             // N/m, every spring
  float damping = 0.0f;               // N s/m, every spring
  float maxForce = 3.0e38f;           // N, every spring
  bool periodic = false;              // the lattice wraps along x (length = the period)
  bool anchorEnds = true;             // non-periodic: the first and last rings are anchored
  float fluidMass = 0.0f;             // kg, SPH mass of every particle
};

struct TubeBuild {
  ParticleSet particles;  // wall particles first (ids 0 .. wall-1), then the fluid
  sim::SpringNetwork network;
  std::uint32_t wall = 0;
  std::uint32_t around = 0;  // points per ring
  std::uint32_t along = 0;   // rings along x
};

// Springs: along x, around, both diagonals of every lattice cell of a layer, and from each
// point to the next layer's point at the same place and its four lattice neighbours there
// (against shearing and bending of the wall); rest lengths are the built distances. Each
// point's normal frame gives the inward normal. Throws std::invalid_argument on bad specs.
TubeBuild buildTube(const TubeSpec& spec);

// The rupture pressure that Laplace's law predicts for this spring layout (Pa): the lumen
// pressure P at which the most stretched spring reaches its maximum force when the tube
// widens uniformly. Virtual work for a uniform radial displacement u of every wall point:
// spring s stretches by g_s u (g_s = dL_s/du, from the built geometry), so equilibrium with
// the pressure on the inner surface 2 pi R L gives P(u) = u sum_s k_s g_s^2 / (2 pi R L), and
// the first spring breaks at u* = min_s f_max,s / (k_s g_s). For the default layout (two
// layers, diagonals of cell dx x c) this is close to P* = 5 f_max / (R dx): per lattice cell,
// the hoop spring, the two shear diagonals of each layer and the two between-layer diagonals
// share the hoop load (docs/physics.md). Meant for periodic tubes (anchored ends stiffen the
// ends). Throws std::invalid_argument if no spring stretches.
double hoopRupturePressure(const TubeSpec& spec, const TubeBuild& tube);

// The hoop stiffness of the layout: the lumen pressure per unit uniform radial displacement,
// sum_s k_s g_s^2 / (2 pi R L) (Pa/m), from the virtual work above.
double hoopStiffness(const TubeSpec& spec, const TubeBuild& tube);

// Springs from tissue properties: the uniform stiffness and maximum force that give the
// built layout the hoop behaviour of a thin elastic tube of Young's modulus E (Pa), Poisson
// ratio nu, wall thickness t (m) and failure (ultimate) stress sigma_f (Pa). A long tube under
// lumen pressure P has hoop stress P R / t and, not stretching along its axis, hoop strain
// (1 - nu^2) P R / (E t): its wall moves out by u = (1 - nu^2) P R^2 / (E t). The lattice moves
// out by u = P 2 pi R L / (k sum g^2), so
//   k = E t 2 pi L / ((1 - nu^2) R sum g^2),
// and it ruptures at P* = sigma_f t / R (Laplace) when
//   f_max = sigma_f t 2 pi L g_max / sum g^2
// (g_s = dL_s/du, g_max the largest). Throws std::invalid_argument for non-positive inputs or
// nu outside [0, 0.5).
struct TissueSprings {
  float stiffness = 0.0f;  // N/m
  float maxForce = 0.0f;   // N
};
TissueSprings springsFromTissue(const TubeSpec& spec, double youngsModulus, double poissonRatio, double thickness,
                                double failureStress);

// The fluid filling of a tube's lumen, one spacing clear of the wall's first layer: slices
// (x0 + (i + 1/2) dx) of concentric rings at radii (k + 1/2) dr (K = round(R / dp) rings,
// dr = R / K, the outer one at R - dr/2), ring k holding round(2 pi r_k / dr) points (one
// per dr^2 of the annulus it stands for), every other slice turned by half a step. Unlike a
// cubic lattice clipped by the circle this reaches the wall all round, so the fluid starts at
// its rest density (the lattice left gaps of up to 1.6 dp at the wall, and the fluid started
// some 15% thin, with no pressure to fill them).
std::vector<glm::dvec3> tubeFluidPoints(const TubeSpec& spec, std::uint32_t slices);

}  // namespace hemo::scene
