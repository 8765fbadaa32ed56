#pragma once
// Measurements taken from a snapshot, shared by the validation tests and hemo-bench.
#include "hemo/sim/simulation.hpp"

namespace hemo::sim {

// Vertical force (N) the fluid exerts on the boundary particles below z = floorZ: the
// reaction of the symmetric pressure term, sum over fluid-boundary pairs of
// -m_b m_f (p_b / rho_b^2 + p_f / rho_f^2) dW/dz. Positive when the fluid pushes down.
double floorLoad(const Snapshot& snapshot, std::uint32_t fluidParticles, double h, float floorZ = 0.0f);

// The same for a lid: the upward force (N) of the fluid on the boundary particles above
// z = lidZ. Positive when the fluid pushes up.
double lidLoad(const Snapshot& snapshot, std::uint32_t fluidParticles, double h, float lidZ);

// Largest distance (m) a fluid particle moved between two snapshots of the same run, over the
// particles that started below z = belowZ (matched by id; no periodic wrapping: for tanks).
double largestDisplacement(const Snapshot& from, const Snapshot& to, double belowZ = 1e30);

// Largest x among fluid particles below z = maxZ (the surge front of a dam break).
double surgeFront(const Snapshot& snapshot, std::uint32_t fluidParticles, float maxZ);

// Least-squares slope dp/dz of the fluid pressure over particles with z below maxZ (Pa/m).
double pressureGradient(const Snapshot& snapshot, std::uint32_t fluidParticles, float maxZ);

// Plane Poiseuille flow between walls at z = 0 and z = L, driven along x: the RMS difference
// between the mean x-velocity of each fluid layer [k dp, (k + 1) dp) and the start-up
// solution (reference::poiseuilleStartup) at the layer's mean height and time t, divided by
// the steady peak F L^2 / (8 nu). Throws std::runtime_error if a layer has no particles.
double poiseuilleProfileError(const Snapshot& snapshot, std::uint32_t fluidParticles, double dp, double L, double F,
                              double nu, double t);

}  // namespace hemo::sim
