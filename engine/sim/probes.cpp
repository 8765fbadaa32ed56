#include "hemo/sim/probes.hpp"

#include "hemo/reference/analytic.hpp"
#include "hemo/reference/sph.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace hemo::sim {

namespace {
// Downward force (N) of the symmetric pressure term on the boundary particles that `pick`
// selects (by their z).
template <class Pick>
double downwardLoad(const Snapshot& s, std::uint32_t fluid, double h, Pick pick) {
  double force = 0.0;
  for (std::size_t b = 0; b < s.positions.size(); ++b) {
    if (s.velocities[b].w == float(ParticleKind::Fluid) || !pick(s.positions[b].z)) continue;
    for (std::uint32_t f = 0; f < fluid; ++f) {
      const glm::dvec3 d = glm::dvec3(s.positions[b]) - glm::dvec3(s.positions[f]);
      const double r = glm::length(d);
      if (r >= 2.0 * h || r == 0.0) continue;
      const glm::dvec2 sb = s.densityPressure[b], sf = s.densityPressure[f];
      force -= double(s.positions[b].w) * double(s.positions[f].w) * (sb.y / (sb.x * sb.x) + sf.y / (sf.x * sf.x)) *
               d.z * (reference::kernelDwdr(r, h) / r);
    }
  }
  return -force;
}
}  // namespace

double floorLoad(const Snapshot& s, std::uint32_t fluid, double h, float floorZ) {
  return downwardLoad(s, fluid, h, [floorZ](float z) { return z < floorZ; });
}

double lidLoad(const Snapshot& s, std::uint32_t fluid, double h, float lidZ) {
  return -downwardLoad(s, fluid, h, [lidZ](float z) { return z > lidZ; });
}

double largestDisplacement(const Snapshot& from, const Snapshot& to, double belowZ) {
  if (to.ids.size() != from.ids.size()) {
    throw std::invalid_argument("largestDisplacement: the snapshots do not hold the same particles");
  }
  std::vector<glm::vec3> start(from.ids.size());
  for (std::size_t i = 0; i < from.ids.size(); ++i) {
    if (from.ids[i] >= start.size()) throw std::invalid_argument("largestDisplacement: an id out of range");
    start[from.ids[i]] = glm::vec3(from.positions[i]);
  }
  double worst = 0.0;
  for (std::size_t i = 0; i < to.ids.size(); ++i) {
    if (to.ids[i] >= start.size()) throw std::invalid_argument("largestDisplacement: an id out of range");
    const glm::vec3 s = start[to.ids[i]];
    if (to.velocities[i].w == float(ParticleKind::Fluid) && s.z < belowZ) {
      worst = std::max(worst, double(glm::length(glm::vec3(to.positions[i]) - s)));
    }
  }
  return worst;
}

double surgeFront(const Snapshot& s, std::uint32_t fluid, float maxZ) {
  double front = -1e30;
  for (std::uint32_t i = 0; i < fluid; ++i) {
    if (s.positions[i].z < maxZ) front = std::max(front, double(s.positions[i].x));
  }
  return front;
}

double pressureGradient(const Snapshot& s, std::uint32_t fluid, float maxZ) {
  double sz = 0, sp = 0, szz = 0, szp = 0;
  double count = 0;
  for (std::uint32_t i = 0; i < fluid; ++i) {
    const double z = s.positions[i].z, p = s.densityPressure[i].y;
    if (z > maxZ) continue;
    sz += z, sp += p, szz += z * z, szp += z * p, count += 1;
  }
  const double denominator = count * szz - sz * sz;
  return denominator > 0 ? (count * szp - sz * sp) / denominator : 0.0;
}

double poiseuilleProfileError(const Snapshot& s, std::uint32_t fluid, double dp, double L, double F, double nu,
                              double t) {
  const int layers = static_cast<int>(std::lround(L / dp));
  std::vector<double> sumU(layers, 0.0), sumZ(layers, 0.0);
  std::vector<int> count(layers, 0);
  for (std::uint32_t i = 0; i < fluid; ++i) {
    const double z = s.positions[i].z;
    const int k = std::clamp(static_cast<int>(std::floor(z / dp)), 0, layers - 1);
    sumU[k] += s.velocities[i].x;
    sumZ[k] += z;
    ++count[k];
  }
  double sq = 0.0;
  for (int k = 0; k < layers; ++k) {
    if (count[k] == 0) throw std::runtime_error("Poiseuille profile: layer " + std::to_string(k) + " has no particles");
    const double z = sumZ[k] / count[k];
    const double err = sumU[k] / count[k] - reference::poiseuilleStartup(z, t, L, F, nu);
    sq += err * err;
  }
  return std::sqrt(sq / layers) / (F * L * L / (8.0 * nu));
}

std::vector<double> radialProfile(const Snapshot& s, double radius, int bins) {
  std::vector<double> sum(std::size_t(bins), 0.0);
  std::vector<int> count(std::size_t(bins), 0);
  for (std::size_t i = 0; i < s.positions.size(); ++i) {
    if (s.velocities[i].w != float(ParticleKind::Fluid)) continue;
    const double r = std::hypot(double(s.positions[i].y), double(s.positions[i].z));
    const int bin = int(r / (radius / bins));
    if (bin >= bins) continue;
    sum[std::size_t(bin)] += s.velocities[i].x;
    ++count[std::size_t(bin)];
  }
  for (std::size_t b = 0; b < sum.size(); ++b) sum[b] /= std::max(count[b], 1);
  return sum;
}

double carreauShearRate(const CarreauYasuda& law, double stress) {
  double lo = 0.0, hi = 1.0;
  while (law.at(hi) * hi < stress) hi *= 2.0;
  for (int k = 0; k < 100; ++k) {
    const double mid = 0.5 * (lo + hi);
    (law.at(mid) * mid < stress ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

std::vector<double> carreauTubeProfile(const CarreauYasuda& law, double rho, double G, double R, int bins) {
  constexpr int kSteps = 4000;  // midpoint rule from the wall inwards
  std::vector<double> u(kSteps + 1, 0.0);
  const double dr = R / kSteps;
  for (int k = kSteps - 1; k >= 0; --k) {
    u[std::size_t(k)] = u[std::size_t(k) + 1] + carreauShearRate(law, rho * G * (k + 0.5) * dr / 2.0) * dr;
  }
  std::vector<double> out(std::size_t(bins), 0.0), weight(std::size_t(bins), 0.0);
  for (int k = 0; k < kSteps; ++k) {
    const double r = (k + 0.5) * dr;
    const auto b = std::size_t(std::min(int(r / (R / bins)), bins - 1));
    out[b] += 0.5 * (u[std::size_t(k)] + u[std::size_t(k) + 1]) * r;
    weight[b] += r;
  }
  for (std::size_t b = 0; b < out.size(); ++b) out[b] /= weight[b];
  return out;
}

}  // namespace hemo::sim
