#pragma once
// Closed-form solutions used to validate the solver.
#include <complex>
#include <cstdint>

namespace hemo::reference {

// Start-up of plane Poiseuille flow: fluid at rest between no-slip walls at z = 0 and z = L,
// driven from t = 0 by a uniform body force F (m/s^2) along the walls, kinematic viscosity
// nu (m^2/s). Velocity along F at height z (0 <= z <= L) and time t (s), from the Fourier
// series of the diffusion equation (as written by Morris, Fox & Zhu 1997, eq. 21):
//   v(z, t) = F / (2 nu) z (L - z)
//           - sum_n 4 F L^2 / (nu pi^3 (2n+1)^3) sin((2n+1) pi z / L) exp(-(2n+1)^2 pi^2 nu t / L^2)
// `terms` terms of the series (the n-th decays like (2n+1)^-3 even at t = 0).
double poiseuilleStartup(double z, double t, double L, double F, double nu, std::uint32_t terms = 200);

// Womersley's oscillating flow in a rigid tube of radius R (Womersley 1955): a pressure gradient
// G(t) = Re(G1 exp(i omega t)) along the axis (G = -dp/dx, Pa/m) drives the mean speed over the
// cross-section U(t) = Re(U1 exp(i omega t)), with
//   U1 = G1 / (i omega rho) (1 - 2 J1(L) / (L J0(L))),   L = i^(3/2) alpha,  alpha = R sqrt(omega rho / mu)
// (Womersley's number; J0, J1 Bessel functions of the first kind, from their power series).
// Returns U1 (m/s, complex amplitude). As alpha -> 0 it tends to Poiseuille's G1 R^2 / (8 mu),
// in phase; for large alpha to G1 / (i omega rho), the inviscid plug lagging by 90 degrees.
std::complex<double> womersleyMeanSpeed(std::complex<double> G1, double omega, double rho, double mu, double R);

}  // namespace hemo::reference
