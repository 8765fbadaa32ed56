#include "hemo/reference/sph.hpp"

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

namespace hemo::reference {

double kernelW(double r, double h) {
  const double q = r / h;
  if (q >= 2.0) return 0.0;
  const double t = 1.0 - 0.5 * q;
  return 21.0 / (16.0 * std::numbers::pi * h * h * h) * t * t * t * t * (2.0 * q + 1.0);
}

double kernelDwdr(double r, double h) {
  const double q = r / h;
  if (q >= 2.0) return 0.0;
  const double t = 1.0 - 0.5 * q;
  return 21.0 / (16.0 * std::numbers::pi * h * h * h) * (-5.0 * q * t * t * t) / h;
}

glm::dvec3 separation(const SphModel& m, const glm::dvec3& xi, const glm::dvec3& xj) {
  glm::dvec3 d = xi - xj;
  for (int a = 0; a < 3; ++a) {
    if (m.period[a] > 0.0) d[a] -= m.period[a] * std::round(d[a] / m.period[a]);
  }
  return d;
}

std::vector<glm::dvec2> densityPressure(const std::vector<SphParticle>& particles, const SphModel& m) {
  std::vector<glm::dvec2> out(particles.size());
  const double support = 2.0 * m.h;
  auto carried = [&](const SphParticle& p) { return p.density > 0.0 ? p.density : m.rho0; };
  for (std::size_t i = 0; i < particles.size(); ++i) {
    if (particles[i].kind != 0) continue;
    double rho = 0.0;
    if (m.continuity) {
      const SphParticle& pi = particles[i];
      const double rhoI = carried(pi), etaSq = 0.01 * m.h * m.h;
      double rate = 0.0, diffused = 0.0;
      for (std::size_t j = 0; j < particles.size(); ++j) {
        const SphParticle& pj = particles[j];
        const glm::dvec3 d = separation(m, pi.x, pj.x);  // x_ij
        const double r = glm::length(d);
        if (j == i || r >= support || r == 0.0) continue;
        const glm::dvec3 gradW = d * (kernelDwdr(r, m.h) / r);
        rate += pj.mass * glm::dot(pi.v - pj.v, gradW);
        if (pj.kind != 0) continue;
        const double rhoJ = carried(pj);
        const double hydro = m.rho0 * (std::pow(std::max(1.0 - m.rho0 * glm::dot(m.gravityOnly, d) / m.taitB, 1e-6), 1.0 / 7.0) - 1.0);
        diffused += 2.0 * ((rhoJ - rhoI) - hydro) * -glm::dot(d, gradW) / (r * r + etaSq) * pj.mass / rhoJ;
      }
      rho = rhoI + m.lastDt * (rate + m.deltaSph * m.h * m.c0 * diffused);
    } else {
      for (const auto& pj : particles) {
        const double r = glm::length(separation(m, particles[i].x, pj.x));
        if (r < support) rho += pj.mass * kernelW(r, m.h);
      }
    }
    double p = m.taitB * (std::pow((m.dfsph ? std::min(rho, m.rho0) : rho) / m.rho0, 7.0) - 1.0) + m.backgroundPressure;
    if (m.clampNegativePressure || m.dfsph) p = std::max(p, 0.0);
    out[i] = {rho, p};
  }
  // Boundary particles: pressure extrapolated from the fluid (Adami et al. 2012).
  for (std::size_t b = 0; b < particles.size(); ++b) {
    if (particles[b].kind == 0) continue;
    double sumW = 0.0, sumP = 0.0;
    glm::dvec3 sumRhoR(0.0);
    for (std::size_t f = 0; f < particles.size(); ++f) {
      if (particles[f].kind != 0) continue;
      const glm::dvec3 d = separation(m, particles[b].x, particles[f].x);
      const double r = glm::length(d);
      if (r >= support) continue;
      const double w = kernelW(r, m.h);
      sumW += w;
      sumP += out[f].y * w;
      sumRhoR += out[f].x * d * w;
    }
    if (sumW <= 0.0) {
      out[b] = {m.rho0, m.backgroundPressure};
      continue;
    }
    if (m.dfsph) {
      out[b] = {m.rho0, std::clamp(sumP / sumW, 0.0, m.backgroundPressure)};
      continue;
    }
    double p = (sumP + glm::dot(m.gravity, sumRhoR)) / sumW;
    if (m.clampNegativePressure) p = std::max(p, 0.0);
    out[b] = {m.rho0 * std::pow(std::max((p - m.backgroundPressure) / m.taitB + 1.0, 1e-6), 1.0 / 7.0), p};
  }
  return out;
}

namespace {
// The velocity gradient g[a][b] = d u_a / d x_b of fluid particle i.
std::array<double, 9> velocityGradient(const std::vector<SphParticle>& particles, const std::vector<glm::dvec2>& rp,
                                       const SphModel& m, std::size_t i) {
  std::array<double, 9> g{};
  const double support = 2.0 * m.h;
  for (std::size_t j = 0; j < particles.size(); ++j) {
    if (j == i) continue;
    const glm::dvec3 d = separation(m, particles[i].x, particles[j].x);
    const double r = glm::length(d);
    if (r >= support || r == 0.0) continue;
    const glm::dvec3 gradW = d * (kernelDwdr(r, m.h) / r);
    const glm::dvec3 du = (particles[j].v - particles[i].v) * (particles[j].mass / rp[j].x);
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) g[std::size_t(a * 3 + b)] += du[a] * gradW[b];
  }
  return g;
}
}  // namespace

std::vector<double> shearRates(const std::vector<SphParticle>& particles, const std::vector<glm::dvec2>& rp,
                               const SphModel& m) {
  std::vector<double> out(particles.size(), 0.0);
  const double support = 2.0 * m.h;
  const auto vv = viscousVelocities(particles, m);
  for (std::size_t i = 0; i < particles.size(); ++i) {
    if (particles[i].kind != 0) continue;
    // G = sum_j V_j (u_j - u_i) (x) gradW (boundary particles' no-slip velocity) and
    // M = sum_j V_j (x_j - x_i) (x) gradW, then G M^-1
    glm::dmat3 g(0.0), mm(0.0);  // (column b, row a)
    for (std::size_t j = 0; j < particles.size(); ++j) {
      if (j == i) continue;
      const glm::dvec3 d = separation(m, particles[i].x, particles[j].x);
      const double r = glm::length(d);
      if (r >= support || r == 0.0) continue;
      const glm::dvec3 gradW = d * (kernelDwdr(r, m.h) / r);
      const double volume = particles[j].mass / rp[j].x;
      g += glm::outerProduct((vv[j] - particles[i].v) * volume, gradW);
      mm -= glm::outerProduct(d * volume, gradW);
    }
    const glm::dmat3 c = glm::determinant(mm) > 0.25 ? g * glm::inverse(mm) : g;
    double s2 = 0.0;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        const double sab = 0.5 * (c[b][a] + c[a][b]);
        s2 += 2.0 * sab * sab;
      }
    out[i] = std::sqrt(s2);
  }
  return out;
}

std::vector<double> viscosities(const std::vector<SphParticle>& particles, const std::vector<glm::dvec2>& rp,
                                const SphModel& m) {
  if (!m.carreauYasuda) return std::vector<double>(particles.size(), m.mu);
  std::vector<double> out = shearRates(particles, rp, m);
  for (std::size_t i = 0; i < particles.size(); ++i) {
    if (particles[i].kind != 0) continue;
    out[i] = m.muInf + (m.mu0 - m.muInf) * std::pow(1.0 + std::pow(m.lambda * out[i], m.yasuda), (m.powerIndex - 1.0) / m.yasuda);
  }
  return out;
}

std::vector<std::array<double, 9>> spsStress(const std::vector<SphParticle>& particles,
                                             const std::vector<glm::dvec2>& rp, const SphModel& m) {
  std::vector<std::array<double, 9>> out(particles.size(), std::array<double, 9>{});
  for (std::size_t i = 0; i < particles.size(); ++i) {
    if (particles[i].kind != 0) continue;
    const auto gv = velocityGradient(particles, rp, m, i);
    double S[3][3], s2 = 0.0, trace = 0.0;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        S[a][b] = 0.5 * (gv[std::size_t(a * 3 + b)] + gv[std::size_t(b * 3 + a)]);
        s2 += 2.0 * S[a][b] * S[a][b];
      }
    for (int a = 0; a < 3; ++a) trace += S[a][a];
    const double nuT = m.spsSmagorinsky * std::sqrt(s2);
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        out[i][std::size_t(a * 3 + b)] = rp[i].x * (2.0 * nuT * (S[a][b] - (a == b ? trace / 3.0 : 0.0)) -
                                                    (a == b ? (2.0 / 3.0) * m.spsBlinn * s2 : 0.0));
      }
  }
  return out;
}

std::vector<glm::dvec3> viscousVelocities(const std::vector<SphParticle>& particles, const SphModel& m) {
  std::vector<glm::dvec3> out(particles.size());
  const double support = 2.0 * m.h;
  for (std::size_t b = 0; b < particles.size(); ++b) {
    out[b] = particles[b].v;
    if (particles[b].kind == 0) continue;
    double sumW = 0.0;
    glm::dvec3 sumV(0.0);
    for (const auto& f : particles) {
      if (f.kind != 0) continue;
      const double r = glm::length(separation(m, particles[b].x, f.x));
      if (r >= support) continue;
      const double w = kernelW(r, m.h);
      sumW += w;
      sumV += f.v * w;
    }
    if (sumW > 0.0) out[b] = 2.0 * particles[b].v - sumV / sumW;
  }
  return out;
}

glm::dvec3 wallShearStress(const std::vector<SphParticle>& particles, const std::vector<glm::dvec2>& rp, const SphModel& m,
                           std::size_t wall, double area) {
  const SphParticle& b = particles[wall];
  const auto vv = viscousVelocities(particles, m);
  const auto mu = viscosities(particles, rp, m);
  const double etaSq = 0.01 * m.h * m.h;
  glm::dvec3 force(0.0);
  for (std::size_t i = 0; i < particles.size(); ++i) {
    const SphParticle& pi = particles[i];
    if (pi.kind != 0) continue;
    const glm::dvec3 d = separation(m, pi.x, b.x);
    const double r = glm::length(d);
    if (r >= 2.0 * m.h || r == 0.0) continue;
    const glm::dvec3 gradW = d * (kernelDwdr(r, m.h) / r);
    // minus m_i times the viscous pair term of accelerations(): V_i V_b 2 mu_i (x_ib . gradW) / (r^2 + eta^2) (v_i - v_b)
    force -= (pi.mass / rp[i].x) * (b.mass / rp[wall].x) * 2.0 * mu[i] * glm::dot(d, gradW) / (r * r + etaSq) * (pi.v - vv[wall]);
  }
  const glm::dvec3 tangential = force - glm::dot(force, b.normal) * b.normal;
  return area > 0.0 ? tangential / area : glm::dvec3(0.0);
}

std::vector<glm::dvec3> accelerations(const std::vector<SphParticle>& particles, const std::vector<glm::dvec2>& rp,
                                      const SphModel& m, std::vector<glm::dvec3>* reactions) {
  std::vector<glm::dvec3> out(particles.size(), glm::dvec3(0.0));
  if (reactions) reactions->assign(particles.size(), glm::dvec3(0.0));
  struct BoundaryPair {
    std::size_t j;
    glm::dvec3 pairAccel, repulsion;
  };
  std::vector<BoundaryPair> boundaryPairs;
  const auto vv = viscousVelocities(particles, m);
  const double support = 2.0 * m.h;
  const double etaSq = 0.01 * m.h * m.h;
  const auto tau = m.sps ? spsStress(particles, rp, m) : std::vector<std::array<double, 9>>();
  const auto mu = viscosities(particles, rp, m);
  for (std::size_t i = 0; i < particles.size(); ++i) {
    const SphParticle& pi = particles[i];
    if (pi.kind != 0) continue;
    glm::dvec3 a(0.0), repulsion(0.0);
    double weight = 0.0;
    boundaryPairs.clear();
    for (std::size_t j = 0; j < particles.size(); ++j) {
      if (j == i) continue;
      const SphParticle& pj = particles[j];
      const glm::dvec3 d = separation(m, pi.x, pj.x);
      const double r = glm::length(d);
      if (r >= support || r == 0.0) continue;
      const glm::dvec3 gradW = d * (kernelDwdr(r, m.h) / r);
      const bool fluidJ = pj.kind == 0;
      // a_i = (1 / rho_i) sum_j V_j [ -(p_i + p_j) gradW + 2 mu (x_ij . gradW) / (r^2 + eta^2) v_ij ],
      // 2 mu = mu_i + mu_j for a fluid pair, 2 mu_i for a boundary pair
      const double volumeJ = pj.mass / rp[j].x;
      const double muPair = mu[i] + (fluidJ ? mu[j] : mu[i]);
      const glm::dvec3 pairAccel = volumeJ / rp[i].x *
                                   (-(rp[i].y + rp[j].y) * gradW +
                                    muPair * glm::dot(d, gradW) / (r * r + etaSq) * (pi.v - vv[j]));
      a += pairAccel;
      if (m.sps && fluidJ) {
        // a += (1 / rho_i) sum_j V_j (tau_i + tau_j) . gradW
        for (int c = 0; c < 3; ++c) {
          double sum = 0.0;
          for (int b = 0; b < 3; ++b) {
            sum += (tau[i][c * 3 + b] + tau[j][c * 3 + b]) * gradW[b];
          }
          a[c] += volumeJ / rp[i].x * sum;
        }
      }
      if (!fluidJ) {
        const double x = glm::dot(d, pj.normal);
        const double y = glm::length(d - x * pj.normal);
        glm::dvec3 push(0.0);
        // Within D in front of the wall particle's plane, less than dp - D behind it (farther
        // behind, the next layer takes over; fluid beyond a thin wall is not pushed through).
        if (x < m.repulsionCutoff && x > m.repulsionCutoff - m.wallSpacing && y < m.wallSpacing && pj.mass > 0.0) {
          const double w = 1.0 - y / m.wallSpacing;
          const double q = std::max(x / (2.0 * m.h), 1.0e-3);
          push = pj.normal * (m.psi * (1.0 - q) / std::sqrt(q) * w);
          repulsion += push;
          weight += w;
        }
        boundaryPairs.push_back({j, pairAccel, push});
      }
    }
    const double scale = 1.0 / std::max(weight, 1.0);
    out[i] = a + repulsion * scale + m.gravity;
    if (reactions) {
      for (const BoundaryPair& b : boundaryPairs) (*reactions)[b.j] -= pi.mass * (b.pairAccel + b.repulsion * scale);
    }
  }
  return out;
}

namespace {
// One DFSPH solve on velocities u (fluid particles; boundary particles keep their own): each
// prediction finds the source s_i = u-divergence term and the stiffness k_i = scale s_i / D_i,
// each correction u_i -= du * sum_j m_j (k_i + k_j) gradW_ij (boundary: k_j = 0).
struct Pair {
  std::size_t j;
  glm::dvec3 mGradW;  // m_j gradW_ij
  bool fluid;
};
std::vector<std::vector<Pair>> dfsphPairs(const std::vector<SphParticle>& particles, const SphModel& m) {
  std::vector<std::vector<Pair>> pairs(particles.size());
  const double support = 2.0 * m.h;
  for (std::size_t i = 0; i < particles.size(); ++i) {
    if (particles[i].kind != 0) continue;
    for (std::size_t j = 0; j < particles.size(); ++j) {
      const glm::dvec3 d = separation(m, particles[i].x, particles[j].x);
      const double r = glm::length(d);
      if (j == i || r >= support || r == 0.0) continue;
      pairs[i].push_back({j, particles[j].mass * d * (kernelDwdr(r, m.h) / r), particles[j].kind == 0});
    }
  }
  return pairs;
}
double dfsphDenominator(const std::vector<Pair>& pairs, double floor) {
  glm::dvec3 sum(0.0);
  double sq = 0.0;
  for (const Pair& p : pairs) {
    sum += p.mGradW;
    if (p.fluid) sq += glm::dot(p.mGradW, p.mGradW);
  }
  return std::max(glm::dot(sum, sum) + sq, floor);
}
}  // namespace

// The iteration both solves share: `corrections` + 1 predictions, each giving every fluid
// particle its stiffness and error (predict(i, u, p_i) -> {k_i, e_i}, u the current values,
// p_i the particle's pressure entry so far), and a
// correction after each but the last, u_i -= sum_j m_j (k_i + k_j) gradW_ij (boundary:
// k_j = 0), adding accumulate(i, k_i) to the particle's pressure entry.
template <class Predict, class Accumulate>
DfsphSolve dfsphIterate(const std::vector<SphParticle>& particles, const std::vector<std::vector<Pair>>& pairs,
                        std::vector<glm::dvec3> values, int corrections, Predict predict, Accumulate accumulate) {
  const std::size_t n = particles.size();
  DfsphSolve out;
  out.values = std::move(values);
  out.pressure.assign(n, 0.0);
  std::vector<double> k(n, 0.0);
  std::size_t fluid = 0;
  for (const auto& p : particles) fluid += p.kind == 0;
  for (int it = 0; it <= corrections; ++it) {
    double error = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      if (particles[i].kind != 0) continue;
      const glm::dvec2 ke = predict(i, out.values, out.pressure[i]);
      k[i] = ke.x;
      error += ke.y;
    }
    out.errors.push_back(error / double(std::max<std::size_t>(fluid, 1)));
    if (it == corrections) break;
    std::vector<glm::dvec3> next = out.values;
    for (std::size_t i = 0; i < n; ++i) {
      if (particles[i].kind != 0) continue;
      glm::dvec3 sum(0.0);
      for (const Pair& p : pairs[i]) sum += (k[i] + (p.fluid ? k[p.j] : 0.0)) * p.mGradW;
      next[i] -= sum;
      out.pressure[i] += accumulate(i, k[i]);
    }
    out.values = next;
  }
  return out;
}

DfsphSolve dfsphDensitySolve(const std::vector<SphParticle>& particles, const std::vector<double>& rho,
                             const std::vector<glm::dvec3>& aNp, double dt, const SphModel& m, double floor,
                             int corrections) {
  const auto pairs = dfsphPairs(particles, m);
  return dfsphIterate(
      particles, pairs, aNp, corrections,
      [&](std::size_t i, const std::vector<glm::dvec3>& a, double pressure) {
        auto vStar = [&](std::size_t j) { return particles[j].kind == 0 ? particles[j].v + dt * a[j] : particles[j].v; };
        double div = 0.0;
        for (const Pair& p : pairs[i]) div += glm::dot(vStar(i) - vStar(p.j), p.mGradW);
        const double residual = std::max(rho[i] + dt * div - m.rho0 - pressure * m.solveCompliance, 0.0);
        const double diagonal = dt * dt * dfsphDenominator(pairs[i], floor) + rho[i] * rho[i] * m.solveCompliance;
        return glm::dvec2(residual / diagonal, std::min(residual / m.rho0, 1.0));
      },
      [&](std::size_t i, double k) { return k * rho[i] * rho[i]; });
}

DfsphSolve dfsphDivergenceSolve(const std::vector<SphParticle>& particles, const SphModel& m, double floor,
                                double lastDt, int corrections) {
  const auto pairs = dfsphPairs(particles, m);
  std::vector<glm::dvec3> v;
  for (const auto& p : particles) v.push_back(p.v);
  return dfsphIterate(
      particles, pairs, std::move(v), corrections,
      [&](std::size_t i, const std::vector<glm::dvec3>& u, double) {
        double div = 0.0;
        for (const Pair& p : pairs[i]) div += glm::dot(u[i] - u[p.j], p.mGradW);
        const double rate = std::max(div, 0.0);
        return glm::dvec2(rate / dfsphDenominator(pairs[i], floor), std::min(rate * lastDt / m.rho0, 1.0));
      },
      [](std::size_t, double k) { return k; });
}

glm::dvec3 fluidMomentum(const std::vector<SphParticle>& particles) {
  glm::dvec3 p(0.0);
  for (const auto& q : particles) {
    if (q.kind == 0) p += q.mass * q.v;
  }
  return p;
}

}  // namespace hemo::reference
