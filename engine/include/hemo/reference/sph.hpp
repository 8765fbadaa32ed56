#pragma once
// CPU double-precision twin of the SPH stages (sph/density.comp, sph/forces.comp,
// sph/integrate.comp), by brute force over all particle pairs. For tests and validation.
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <array>
#include <vector>

namespace hemo::reference {

struct SphParticle {
  glm::dvec3 x{0.0};
  glm::dvec3 v{0.0};
  glm::dvec3 normal{0.0};  // boundary particles: unit normal into the fluid
  double mass = 0.0;
  int kind = 0;  // 0 fluid, 1 boundary
  double density = 0.0;  // the density a fluid particle carries (continuity density); 0 reads as rho0
};

struct SphModel {
  glm::dvec3 gravity{0.0};  // gravity + body force (m/s^2)
  double h = 0.0;
  double rho0 = 1000.0;
  double taitB = 0.0;
  double mu = 0.0;
  double psi = 0.0;
  double repulsionCutoff = 0.0;
  double wallSpacing = 0.0;
  bool clampNegativePressure = true;
  bool sps = false;              // sub-particle-scale stress (Dalrymple & Rogers 2006)
  double spsSmagorinsky = 0.0;   // (C_s dp)^2
  double spsBlinn = 0.0;         // C_I dp^2
  glm::dvec3 period{0.0};        // m on periodic axes (minimum image), 0 on the others
  double backgroundPressure = 0.0;  // Pa, added to the Tait pressure (already ramped)
  // Continuity density (sph/density.comp): rho_i = carried + lastDt * d rho_i / dt, with the
  // delta-SPH diffusion term (coefficient deltaSph, sound speed c0) less its hydrostatic part.
  bool continuity = false;
  double deltaSph = 0.0;
  double c0 = 0.0;
  glm::dvec3 gravityOnly{0.0};  // gravity without the body force (m/s^2)
  double lastDt = 0.0;          // s
  // DFSPH's density pass (common/tait.glsl, hemo_expansion_pressure): the Tait law on
  // expansion only, p = max(B ((min(rho, rho0) / rho0)^7 - 1) + p_bg, 0); boundary particles
  // take rho0 and their fluid neighbours' kernel-weighted mean pressure, within [0, p_bg].
  bool dfsph = false;
  // DFSPH's density solve: the compliance 1 / c0^2 (s^2 m^-2) its residual
  // rho* - rho0 - p / c0^2 holds, p the solve's own pressure so far; 0: incompressible.
  double solveCompliance = 0.0;
  // Non-Newtonian blood (interface/sph.h, "Viscosity"): each fluid particle's viscosity
  // muInf + (mu0 - muInf) (1 + (lambda |S|)^a)^((n - 1) / a) at its shear rate (shearRates());
  // a fluid pair's viscous term takes mu_i + mu_j and a
  // pair with a boundary particle 2 mu_i, where the Newtonian term takes 2 mu.
  bool carreauYasuda = false;
  double mu0 = 0.0, muInf = 0.0, lambda = 0.0, powerIndex = 1.0, yasuda = 2.0;
};

// x_i - x_j, by the minimum image on periodic axes.
glm::dvec3 separation(const SphModel& model, const glm::dvec3& xi, const glm::dvec3& xj);

// SPS stress tau (Pa, symmetric 3x3, row-major) of each particle (zero for
// boundary particles).
std::vector<std::array<double, 9>> spsStress(const std::vector<SphParticle>& particles,
                                             const std::vector<glm::dvec2>& densityPressure, const SphModel& model);

// The shear rate |S| = sqrt(2 S:S) (1/s) of each fluid particle (0 for boundary particles), with
// S the symmetric part of the corrected velocity gradient G M^-1 (interface/sph.h, "Viscosity"):
// G = sum_j V_j (u_j - u_i) (x) gradW_ij with boundary particles' no-slip velocities
// (viscousVelocities()), M = sum_j V_j (x_j - x_i) (x) gradW_ij; G alone where det M < 1/4.
std::vector<double> shearRates(const std::vector<SphParticle>& particles, const std::vector<glm::dvec2>& densityPressure,
                               const SphModel& model);

// Each particle's viscosity (Pa s): model.mu, or with model.carreauYasuda the law at its shear
// rate (fluid particles; boundary particles 0).
std::vector<double> viscosities(const std::vector<SphParticle>& particles, const std::vector<glm::dvec2>& densityPressure,
                                const SphModel& model);

// Wendland C2 in 3D with support 2h.
double kernelW(double r, double h);
double kernelDwdr(double r, double h);

// (rho, p) per particle; boundary particles get the pressure extrapolated from their fluid
// neighbours (Adami et al. 2012) and the matching Tait density.
std::vector<glm::dvec2> densityPressure(const std::vector<SphParticle>& particles, const SphModel& model);

// The velocity each particle shows the viscous term: its own for fluid particles; for boundary
// particles with fluid neighbours 2 v_b - (sum_f v_f W_bf) / (sum_f W_bf), the no-slip
// extrapolation of Adami, Hu & Adams (2012, eq. 22-23).
std::vector<glm::dvec3> viscousVelocities(const std::vector<SphParticle>& particles, const SphModel& model);

// The wall shear stress (Pa, a vector) boundary particle `wall` carries (wall/spring_forces.comp):
// the viscous part of the force the fluid exerts on it (minus the viscous pair terms of
// accelerations(), times the fluid's masses), less its part along the particle's normal, over
// the lumen area `area` (m^2) it carries.
glm::dvec3 wallShearStress(const std::vector<SphParticle>& particles, const std::vector<glm::dvec2>& densityPressure,
                           const SphModel& model, std::size_t wall, double area);

// Acceleration per particle (zero for boundary particles). With `reactions`, also the force
// (N) on each boundary particle: minus the sum of m_f times the pair terms each fluid
// particle f got from it (pressure, viscosity, its share of the normalised repulsion).
std::vector<glm::dvec3> accelerations(const std::vector<SphParticle>& particles,
                                      const std::vector<glm::dvec2>& densityPressure, const SphModel& model,
                                      std::vector<glm::dvec3>* reactions = nullptr);

// DFSPH's two solves (sph/dfsph_*.comp; interface/sph.h, "The pressure solver"), a fixed
// number of corrections each (the GPU's tolerance test aside). `rho`: the summed density per
// particle (fluid); `floor`: SphParams::solveFloor.
struct DfsphSolve {
  std::vector<glm::dvec3> values;  // density solve: a_np + a_p; divergence solve: the velocities
  std::vector<double> pressure;    // density solve: sum of k_i rho_i^2 over the corrections (Pa);
                                   // divergence solve: sum of k_i (m^5 kg^-1 s^-1)
  std::vector<double> errors;      // the mean error / rho0 of each prediction (corrections + 1)
};
// The density solve: accelerations a_np (fluid) with the step dt.
DfsphSolve dfsphDensitySolve(const std::vector<SphParticle>& particles, const std::vector<double>& rho,
                             const std::vector<glm::dvec3>& aNp, double dt, const SphModel& model, double floor,
                             int corrections);
// The divergence solve of the particles' velocities; the errors scaled by the last step's dt.
DfsphSolve dfsphDivergenceSolve(const std::vector<SphParticle>& particles, const SphModel& model, double floor,
                                double lastDt, int corrections);

// Total linear momentum of the fluid particles.
glm::dvec3 fluidMomentum(const std::vector<SphParticle>& particles);

}  // namespace hemo::reference
