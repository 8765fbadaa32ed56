#pragma once
// A saccular aneurysm: a spherical sac on the side (+z) of a straight tube (the seed paper's
// Fig. 3 model). The tube part is buildTube's lattice and springs; the sac is a layered
// Fibonacci sphere whose points are joined to their nearest neighbours (a triangulated
// membrane) and to the tube's points at the neck. The sac's springs may be softer and weaker
// than the tube's: aneurysm walls are thinner and their collagen is degraded.
#include "hemo/scene/tube.hpp"

#include <glm/vec3.hpp>

#include <cstdint>
#include <memory>
#include <vector>

namespace hemo::scene {

class VesselMesh;

struct AneurysmSpec {
  TubeSpec tube;                   // the parent vessel (its springs' parameters too)
  float sacRadius = 0.0f;          // m, inner radius of the sac
  float neckWidth = 0.0f;          // m, diameter of the opening between tube and sac
  float sacStiffnessScale = 1.0f;  // sac springs: stiffness = scale x the tube's
  float sacStrengthScale = 1.0f;   // sac springs: maximum force = scale x the tube's
  // A fusiform aneurysm instead (hemo/scene/fusiform.hpp; sacRadius 0): the tube bulges to
  // this inner radius halfway along, over this axial length; the bulge's springs take the
  // sac's scales.
  float bulgeRadius = 0.0f;        // m
  float bulgeLength = 0.0f;        // m
  // A bifurcation instead (hemo/scene/bifurcation.hpp; branchLength > 0): two branches at
  // +-branchAngle to the axis that bend back and merge again halfway along a periodic tube.
  float branchAngle = 0.0f;        // rad
  float branchLength = 0.0f;       // m, each leg
  // A vessel from a surface mesh instead (hemo/scene/mesh_vessel.hpp): the tube's spacing,
  // layers and spring parameters apply; x0 and length give the periodic span.
  std::shared_ptr<const VesselMesh> mesh;
  // Mesh vessels: spheres (centre xyz m, radius m) where the springs take other scales
  // (stiffness, strength); the first that holds a spring's midpoint applies.
  struct Region {
    glm::dvec3 centre{0.0};
    double radius = 0.0;
    float stiffnessScale = 1.0f, strengthScale = 1.0f;
  };
  std::vector<Region> regions;
  // Mesh vessels with open ends (vessel.outlet, hemo/sim/inflow.hpp): the domain is not
  // periodic, and the wall points within a spacing of an end are anchored (the vessel goes on
  // beyond its cut, as the analytic tube's anchored end rings).
  bool openEnds = false;
};

// The inner radius (m) of the vessel at axial position x: the tube's, or on a fusiform
// aneurysm R + (Rb - R) cos^2(pi (x - xc) / Lb) within Lb / 2 of the tube's middle xc.
double innerRadiusAt(const AneurysmSpec& spec, double x);

struct AneurysmBuild {
  ParticleSet particles;  // wall particles first (ids 0 .. wall-1), then the fluid
  sim::SpringNetwork network;
  std::uint32_t wall = 0;
  std::vector<std::uint8_t> inSac;  // per wall point: 1 if it belongs to the sac
  glm::vec3 sacCentre{0.0f};        // m
  double sacInnerArea = 0.0;        // m^2: 4 pi Rs^2 x the kept fraction of the sac's inner layer
};

// Distance (m) from the tube's axis to the sac's centre: the inner surfaces (radii R and Rs)
// meet at width w in the cross-section through the centre. Needs w < 2R and w < 2Rs.
double sacCentreOffset(double tubeRadius, double sacRadius, double neckWidth);

// The sac sits halfway along the tube, its centre at distance
// sqrt(R^2 - w^2/4) + sqrt(Rs^2 - w^2/4) from the axis (the inner surfaces meet at width w in
// the cross-section through the centre). A spring is a sac spring if either end is a sac
// point. Throws std::invalid_argument on bad specs (naming the parameter).
AneurysmBuild buildSaccularAneurysm(const AneurysmSpec& spec);

// Whether `p` lies outside the vessel's outer wall surface (by more than `margin` m), in the
// built geometry: fluid there has left the vessel. A spec with sacRadius 0 is a plain tube
// (or a fusiform aneurysm, or a bifurcation when branchLength > 0).
bool outsideVessel(const AneurysmSpec& spec, glm::vec3 p, float margin);

// The lumen pressure (Pa) at which the sac's most stretched spring reaches its maximum force
// when the sac widens uniformly about its centre, by the virtual work of the sac springs
// alone (as hoopRupturePressure for a tube): P* = u* sum k g^2 / A, with A the sac's inner
// area (its kept fraction of the sphere). Laplace's law for a sphere (T = P r / 2) is why a
// sac of radius Rs fails at a lower pressure than a tube of radius R < Rs / 2 made of the
// same springs.
double sacRupturePressure(const AneurysmBuild& build);

}  // namespace hemo::scene
