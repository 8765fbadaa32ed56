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
float hemo_repulsion(float x, float y, float h, float psi, float cutoff, float wallSpacing, out float weight) {
  weight = 0.0;
  if (!(x < cutoff && x > cutoff - wallSpacing && y < wallSpacing)) {
    return 0.0;
  }
  weight = 1.0 - y / wallSpacing;
  const float q = max(x / (2.0 * h), 1.0e-3);
  return psi * (1.0 - q) / sqrt(q) * weight;
}
