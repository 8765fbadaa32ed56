// The improved repulsive boundary force of a wall (or boundary) particle on a fluid particle,
// F = n N(x) T(y) (docs/physics.md), shared by the fluid's force pass (sph/forces.comp) and the
// wall's reaction (wall/spring_forces.comp) so that both see the same force.
//   x: normal distance of the fluid particle in front of the wall particle's plane (m)
//   y: its distance along the plane (m)
// Returns N(x) T(y) (m/s^2) and T(y) in `weight`; both 0 outside the force's reach: within D
// in front of the plane, and behind it by less than dp - D (a particle farther behind is
// within D of the next layer, which takes over; fluid on the far side of a thin part of the
// wall, such as the blade between a bifurcation's branches, is not pushed through it).
// q = x / 2h is kept >= 1e-3, so a particle at (or just behind) the plane is pushed out with a
// large but finite force.
// The parameters with their reciprocals, computed once per invocation: the pair loops then
// multiply where they would divide (a vector division or square root is the costliest
// arithmetic of the force pass on lavapipe).
struct HemoRepulsionParams {
  float psi;             // Psi (m/s^2)
  float cutoff;          // D (m)
  float wallSpacing;     // dp (m)
  float invWallSpacing;  // 1 / dp
  float invTwoH;         // 1 / 2h
};

HemoRepulsionParams hemo_repulsion_params(float h, float psi, float cutoff, float wallSpacing) {
  return HemoRepulsionParams(psi, cutoff, wallSpacing, 1.0 / wallSpacing, 0.5 / h);
}

float hemo_repulsion(float x, float y, HemoRepulsionParams rp, out float weight) {
  weight = 0.0;
  if (!(x < rp.cutoff && x > rp.cutoff - rp.wallSpacing && y < rp.wallSpacing)) {
    return 0.0;
  }
  weight = 1.0 - y * rp.invWallSpacing;
  const float q = max(x * rp.invTwoH, 1.0e-3);
  return rp.psi * (1.0 - q) * inversesqrt(q) * weight;
}

// The farthest a fluid particle feels the repulsion of a boundary particle, |x_ij| at most,
// from the reach hemo_repulsion tests: |x| < max(D, dp - D) and y < dp (m).
float hemo_repulsion_reach(float cutoff, float wallSpacing) {
  const float normal = max(cutoff, wallSpacing - cutoff);
  return sqrt(normal * normal + wallSpacing * wallSpacing);
}
