#pragma once
// The shipped vessel scenes' parent artery for the builder tests: dp 0.35 mm, R = 5 dp, two
// wall layers, the interactive preset's springs, periodic, `spacings` dp long.
#include "hemo/scene/tube.hpp"

namespace hemo::scene {

inline TubeSpec arteryTube(int spacings) {
  TubeSpec t;
  t.spacing = 3.5e-4f;
  t.length = float(spacings) * t.spacing;
  t.radius = 5 * t.spacing;
  t.layers = 2;
  t.pointMass = 5e-6f;
  t.stiffness = 5.0f;
  t.damping = 2e-3f;
  t.maxForce = 1.65e-4f;
  t.periodic = true;
  t.fluidMass = 4.5e-8f;
  return t;
}

}  // namespace hemo::scene
