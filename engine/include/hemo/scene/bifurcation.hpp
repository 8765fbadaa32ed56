#pragma once
// A bifurcation: the parent tube splits into two branches that leave its axis at +-theta in
// the x-y plane and, after `branchLength`, bend back at -+theta to merge on the axis again
// (an arterial loop, like a fenestration or a segment of the circle of Willis). The loop sits
// halfway along a periodic parent, so what leaves the merge comes back through the periodic
// seam to the inflow zone: the vessel runs for as long as wanted with a fixed particle count.
// With open ends (AneurysmSpec::openEnds) the same vessel is cut at the seam: the parent
// starts at x0 and ends at x0 + L, nothing links across the cut, and the wall points within a
// spacing of either end are anchored.
//
// The lumen is a union of capsules (cylinders with spherical ends) of the tube's radius: the
// parent (from the merge, across the seam, to the split) and the four branch legs, with the
// spheres at the split, the two bends and the merge closing every joint (where two
// cylinders meet at an angle, their end caps leave a wedge on the outer side that the sphere
// covers). Each wall layer l is the boundary of the same union at radius R + (l + 1/2) dp:
// every element's surface is sampled (cylinders in rings of round(2 pi r / dp) points one
// spacing apart, alternate rings turned by half a step; spheres as Fibonacci spheres of
// round(4 pi r^2 / dp^2) points), and a point is kept when it is not inside another element
// of its layer and not within 0.6 dp of a point kept before it (cylinders first). Springs join
// every pair of wall points nearer than 1.5 dp, so the seams (the carina between the branches
// included) are stitched like the rest. The fluid: rings per slice along every leg and
// Fibonacci shells about every joint, each point clear of the wall and of the fluid kept
// before it by 0.8 dp.
#include "hemo/scene/aneurysm.hpp"

#include <glm/vec3.hpp>

#include <cstdint>
#include <vector>

namespace hemo::scene {

// The union's elements in unwrapped coordinates (the parent runs from the merge to the split
// plus one period; distances take the nearest periodic image along x).
struct BifurcationGeometry {
  struct Segment {
    glm::dvec3 a, b;  // m, the axis from a to b
  };
  std::vector<Segment> segments;  // parent, split -> +bend, +bend -> merge, split -> -bend, -bend -> merge
  std::vector<glm::dvec3> joints;  // split, +bend, merge, -bend
  double period = 0.0;             // m along x
};

// Throws std::invalid_argument on bad specs (naming the parameter). Needs a periodic tube (or
// open ends),
// theta in (0, 80] degrees, and branches far enough apart at the bends that the loop opens
// (2 L sin theta >= 2 (R + layers dp) + dp) and short enough to fit in the tube with a
// straight parent of at least 4 dp.
BifurcationGeometry bifurcationGeometry(const AneurysmSpec& spec);

// Signed distance (m) from p to the union's surface at this radius (negative inside).
double bifurcationDistance(const BifurcationGeometry& g, glm::dvec3 p, double radius);

struct BifurcationBuild {
  ParticleSet particles;  // wall particles first (ids 0 .. wall-1), then the fluid
  sim::SpringNetwork network;
  std::uint32_t wall = 0;
  BifurcationGeometry geometry;
  // Per wall point: the element it was sampled on (0 parent, 1-4 the legs, 5-8 the joints in
  // the order of `geometry.joints`) and its layer.
  std::vector<std::uint8_t> element;
  std::vector<std::uint8_t> layer;
};

BifurcationBuild buildBifurcation(const AneurysmSpec& spec);

}  // namespace hemo::scene
