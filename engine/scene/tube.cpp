#include "hemo/scene/tube.hpp"

#include "interface/sph.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

namespace hemo::scene {

TubeBuild buildTube(const TubeSpec& t) {
  auto positive = [](float v) { return std::isfinite(v) && v > 0.0f; };
  if (!positive(t.spacing) || !positive(t.radius) || !positive(t.length) || !positive(t.pointMass) ||
      !positive(t.fluidMass)) {
    throw std::invalid_argument("tube: spacing, radius, length and masses must be positive");
  }
  if (t.layers < 1 || t.layers > 4) throw std::invalid_argument("tube: layers must be 1 to 4");
  if (t.radius < 2.0f * t.spacing) throw std::invalid_argument("tube: the radius must be at least two spacings");
  const double dp = t.spacing;
  const auto along = static_cast<std::uint32_t>(std::lround(t.length / dp));
  if (t.periodic && std::abs(double(along) * dp - t.length) > 1e-3 * dp) {
    throw std::invalid_argument("tube: a periodic tube's length must be a whole number of spacings");
  }
  const auto around = static_cast<std::uint32_t>(std::lround(2.0 * std::numbers::pi * t.radius / dp));
  if (along < 3 || around < 8) throw std::invalid_argument("tube: too short or too thin for its spacing");
  const double dx = double(t.length) / along;

  TubeBuild b;
  b.along = along;
  b.around = around;
  auto id = [&](std::uint32_t i, std::uint32_t k, std::uint32_t l) { return (l * along + i) * around + k; };
  auto position = [&](std::uint32_t i, std::uint32_t k, std::uint32_t l) {
    const double r = t.radius + (l + 0.5) * dp;
    const double theta = 2.0 * std::numbers::pi * k / around;
    return glm::dvec3(t.x0 + (i + 0.5) * dx, t.centreYZ.x + r * std::cos(theta), t.centreYZ.y + r * std::sin(theta));
  };
  // Separation b - a along the tube, across the seam if periodic.
  auto separation = [&](glm::dvec3 a, glm::dvec3 bb) {
    glm::dvec3 d = bb - a;
    if (t.periodic) d.x -= double(t.length) * std::round(d.x / t.length);
    return d;
  };
  ParticleSet& set = b.particles;
  for (std::uint32_t l = 0; l < t.layers; ++l)
    for (std::uint32_t i = 0; i < along; ++i)
      for (std::uint32_t k = 0; k < around; ++k) {
        const glm::dvec3 p = position(i, k, l);
        const glm::dvec3 inward = glm::normalize(glm::dvec3(0.0, t.centreYZ.x - p.y, t.centreYZ.y - p.z));
        set.add(glm::vec3(p), t.fluidMass, float(HEMO_KIND_WALL), glm::vec3(inward));
        sim::WallPoint w;
        w.mass = t.pointMass;
        w.anchored = !t.periodic && t.anchorEnds && (i == 0 || i + 1 == along);
        // Inward normal: (x_A - x) x (x_B - x) with A the next point along x and B the next
        // around (x-hat x theta-hat points to the axis); at the last ring, the previous along x
        // with the order swapped.
        const bool last = !t.periodic && i + 1 == along;
        const std::uint32_t alongNext = last ? id(i - 1, k, l) : id((i + 1) % along, k, l);
        const std::uint32_t aroundNext = id(i, (k + 1) % around, l);
        w.frameA = last ? aroundNext : alongNext;
        w.frameB = last ? alongNext : aroundNext;
        b.network.points.push_back(w);
      }
  b.wall = static_cast<std::uint32_t>(set.positions.size());
  auto link = [&](std::uint32_t a, std::uint32_t c) {
    const double rest = glm::length(separation(glm::dvec3(set.positions[a]), glm::dvec3(set.positions[c])));
    b.network.springs.push_back({a, c, float(rest), t.stiffness, t.damping, t.maxForce});
  };
  const std::uint32_t rings = t.periodic ? along : along - 1;  // cells along x
  for (std::uint32_t l = 0; l < t.layers; ++l)
    for (std::uint32_t i = 0; i < along; ++i)
      for (std::uint32_t k = 0; k < around; ++k) {
        const std::uint32_t k1 = (k + 1) % around;
        link(id(i, k, l), id(i, k1, l));  // around
        if (i < rings) {
          const std::uint32_t i1 = (i + 1) % along;
          link(id(i, k, l), id(i1, k, l));    // along
          link(id(i, k, l), id(i1, k1, l));   // shear diagonals
          link(id(i, k1, l), id(i1, k, l));
        }
        if (l + 1 < t.layers) {  // to the next layer: straight out and to its four neighbours
          link(id(i, k, l), id(i, k, l + 1));
          link(id(i, k, l), id(i, k1, l + 1));
          link(id(i, k, l), id(i, (k + around - 1) % around, l + 1));
          if (t.periodic || i + 1 < along) link(id(i, k, l), id((i + 1) % along, k, l + 1));
          if (t.periodic || i > 0) link(id(i, k, l), id((i + along - 1) % along, k, l + 1));
        }
      }
  for (const glm::dvec3& p : tubeFluidPoints(t, along)) set.add(glm::vec3(p), t.fluidMass, float(HEMO_KIND_FLUID));
  set.fluid = set.size() - b.wall;
  set.boundary = 0;
  set.numberIds();
  b.network.validate();
  return b;
}

std::vector<glm::dvec3> tubeFluidPoints(const TubeSpec& t, std::uint32_t slices) {
  const double dp = t.spacing, dx = double(t.length) / slices;
  const auto rings = static_cast<std::uint32_t>(std::max(1L, std::lround(t.radius / dp)));
  const double dr = double(t.radius) / rings;
  std::vector<glm::dvec3> points;
  for (std::uint32_t i = 0; i < slices; ++i)
    for (std::uint32_t k = 0; k < rings; ++k) {
      const double r = (k + 0.5) * dr;
      const auto count = static_cast<std::uint32_t>(std::max(1L, std::lround(2.0 * std::numbers::pi * r / dr)));
      for (std::uint32_t m = 0; m < count; ++m) {
        const double theta = 2.0 * std::numbers::pi * (m + 0.5 * (i % 2)) / count;
        points.emplace_back(t.x0 + (i + 0.5) * dx, t.centreYZ.x + r * std::cos(theta), t.centreYZ.y + r * std::sin(theta));
      }
    }
  return points;
}

namespace {
struct HoopSums {
  double sumKg2 = 0.0;  // sum_s k_s g_s^2 (N/m)
  double uStar = std::numeric_limits<double>::infinity();  // m: the first spring's break
  double gMax = 0.0;
};
HoopSums hoopSums(const TubeSpec& t, const TubeBuild& b) {
  const auto& pos = b.particles.positions;
  auto radial = [&](std::uint32_t i) {
    return glm::normalize(glm::dvec3(0.0, double(pos[i].y) - t.centreYZ.x, double(pos[i].z) - t.centreYZ.y));
  };
  HoopSums h;
  for (const sim::Spring& s : b.network.springs) {
    glm::dvec3 d = glm::dvec3(pos[s.b]) - glm::dvec3(pos[s.a]);
    if (t.periodic) d.x -= double(t.length) * std::round(d.x / t.length);
    const double g = glm::dot(glm::normalize(d), radial(s.b) - radial(s.a));  // dL/du
    h.sumKg2 += double(s.stiffness) * g * g;
    h.gMax = std::max(h.gMax, g);
    if (g > 1e-9 && s.stiffness > 0.0f) h.uStar = std::min(h.uStar, double(s.maxForce) / (double(s.stiffness) * g));
  }
  return h;
}
}  // namespace

double hoopRupturePressure(const TubeSpec& t, const TubeBuild& b) {
  const HoopSums h = hoopSums(t, b);
  if (!std::isfinite(h.uStar) || h.sumKg2 <= 0.0) throw std::invalid_argument("tube: no spring stretches when it widens");
  return h.uStar * h.sumKg2 / (2.0 * std::numbers::pi * double(t.radius) * double(t.length));
}

double hoopStiffness(const TubeSpec& t, const TubeBuild& b) {
  return hoopSums(t, b).sumKg2 / (2.0 * std::numbers::pi * double(t.radius) * double(t.length));
}

TissueSprings springsFromTissue(const TubeSpec& spec, double E, double nu, double thickness, double sigmaF) {
  auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  if (!positive(E) || !positive(thickness) || !positive(sigmaF)) {
    throw std::invalid_argument("tissue: Young's modulus, wall thickness and failure stress must be positive");
  }
  if (!(std::isfinite(nu) && nu >= 0.0 && nu < 0.5)) throw std::invalid_argument("tissue: Poisson's ratio must be in [0, 0.5)");
  TubeSpec unit = spec;
  unit.stiffness = 1.0f;
  unit.maxForce = 1.0f;
  const HoopSums h = hoopSums(unit, buildTube(unit));
  if (h.sumKg2 <= 0.0 || h.gMax <= 0.0) throw std::invalid_argument("tube: no spring stretches when it widens");
  const double twoPiL = 2.0 * std::numbers::pi * double(spec.length);
  TissueSprings out;
  out.stiffness = float(E * thickness * twoPiL / ((1.0 - nu * nu) * double(spec.radius) * h.sumKg2));
  out.maxForce = float(sigmaF * thickness * twoPiL * h.gMax / h.sumKg2);
  return out;
}

}  // namespace hemo::scene
