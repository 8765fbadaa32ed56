#pragma once
// The reference model (engine/reference/sph.hpp) of a solver's parameter block, for tests that
// compare GPU stages with the double-precision twins.
#include "hemo/reference/sph.hpp"
#include "hemo/sim/sph.hpp"

#include <algorithm>

namespace hemo::test {

// `time`: the solver's clock (s), for the ramped background pressure.
inline reference::SphModel modelOf(const sim::SphParams& p, double time = 0.0) {
  reference::SphModel m;
  m.gravity = {p.gravity[0], p.gravity[1], p.gravity[2]};
  m.h = p.h;
  m.rho0 = p.rho0;
  m.taitB = p.taitB;
  m.mu = p.mu;
  m.psi = p.psi;
  m.repulsionCutoff = p.repulsionCutoff;
  m.wallSpacing = p.wallSpacing;
  m.clampNegativePressure = p.clampNegativePressure != 0;
  m.sps = p.spsEnabled != 0;
  m.spsSmagorinsky = p.spsSmagorinsky;
  m.spsBlinn = p.spsBlinn;
  m.period = {p.period[0], p.period[1], p.period[2]};
  const double ramp = p.backgroundRamp > 0.0f ? std::clamp(time / p.backgroundRamp, 0.0, 1.0) : 1.0;
  m.backgroundPressure = p.backgroundPressure * ramp;
  m.deltaSph = p.deltaSph;
  m.c0 = p.c0;
  m.dfsph = p.pressureSolver != 0;
  m.solveCompliance = p.solveCompliance;
  m.gravityOnly = {p.gravityOnly[0], p.gravityOnly[1], p.gravityOnly[2]};
  m.carreauYasuda = p.carreau[2] > 0.0f;  // (lambda is positive for non-Newtonian blood, else 0)
  m.muInf = p.carreau[0];
  m.mu0 = double(p.carreau[0]) + p.carreau[1];
  m.lambda = p.carreau[2];
  m.yasuda = p.carreau[3];
  m.powerIndex = 1.0 + double(p.rheologyExponent) * p.carreau[3];
  return m;
}

}  // namespace hemo::test
