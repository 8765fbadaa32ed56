#pragma once
// Measurements taken from a snapshot, shared by the validation tests and hemo-bench.
#include "hemo/sim/simulation.hpp"

#include <vector>

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

// Flow along x in a straight tube whose axis is the x axis (y = z = 0): the mean x-velocity of
// the fluid in each of `bins` radial bins of width radius / bins (m/s; 0 for an empty bin).
std::vector<double> radialProfile(const Snapshot& snapshot, double radius, int bins);

// Steady flow of a Carreau-Yasuda fluid (density rho) in a tube of radius R driven by a body
// force G (m/s^2) along it. The shear stress is rho G r / 2 at radius r whatever the fluid, so
// the shear rate g(r) solves mu(g) g = rho G r / 2 (mu(g) g grows with g for n > 0), and
// u(r) = integral of g from r to R. carreauShearRate solves the first (1/s, by bisection);
// carreauTubeProfile gives u averaged over each of `bins` annuli of equal width (weight r),
// as radialProfile measures it.
double carreauShearRate(const CarreauYasuda& law, double stress);
std::vector<double> carreauTubeProfile(const CarreauYasuda& law, double rho, double G, double R, int bins);

}  // namespace hemo::sim
