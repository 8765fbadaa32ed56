#pragma once
// A fusiform aneurysm: the tube bulges all round over part of its length (inner radius
// innerRadiusAt: R + (Rb - R) cos^2(pi (x - xc) / Lb) within Lb / 2 of the middle xc). The
// wall is a surface of revolution of `layers` layers at radius r(x) + (l + 1/2) dp, sampled
// in rings at equal arc length along the inner layer's profile (so the spacing along the wall
// stays dp on the bulge's flanks), each ring holding round(2 pi r / dp) points, alternate
// rings turned by half a step. Springs join every pair of wall points nearer than 1.5 dp (the
// in-layer neighbours at about 1-1.2 dp, and the nearest points of the next layer); springs
// with an end on the bulge take the bulge's stiffness and strength scales (AneurysmSpec's sac
// scales). The fluid: rings of the local radius per slice (as tubeFluidPoints), clear of the
// wall by 0.8 dp.
#include "hemo/scene/aneurysm.hpp"

namespace hemo::scene {

struct FusiformBuild {
  ParticleSet particles;  // wall particles first (ids 0 .. wall-1), then the fluid
  sim::SpringNetwork network;
  std::uint32_t wall = 0;
  std::vector<std::uint8_t> inBulge;  // per wall point: 1 within the bulge (|x - xc| < Lb / 2)
  double bulgeInnerArea = 0.0;        // m^2: the bulge's inner surface
};

// Throws std::invalid_argument on bad specs (naming the parameter).
FusiformBuild buildFusiformAneurysm(const AneurysmSpec& spec);

}  // namespace hemo::scene
