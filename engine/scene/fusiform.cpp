#include "hemo/scene/fusiform.hpp"

#include "interface/sph.h"
#include "wall_links.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

namespace hemo::scene {

namespace {

constexpr double kLinkRadius = 1.5;      // spacings: springs join wall points nearer than this
constexpr double kFluidClearance = 0.8;  // spacings: no fluid nearer than this to a wall point

double slopeAt(const AneurysmSpec& a, double x) {
  const double h = 1e-4 * a.tube.spacing;
  return (innerRadiusAt(a, x + h) - innerRadiusAt(a, x - h)) / (2.0 * h);
}

// Outward unit normal of the surface of revolution r(x) at axial position x and angle theta.
glm::dvec3 outwardNormal(const AneurysmSpec& a, double x, double theta) {
  const double s = slopeAt(a, x);
  return glm::dvec3(-s, std::cos(theta), std::sin(theta)) / std::sqrt(1.0 + s * s);
}

void check(const AneurysmSpec& a) {
  const TubeSpec& t = a.tube;
  auto positive = [](float v) { return std::isfinite(v) && v > 0.0f; };
  if (!positive(a.bulgeRadius) || !(a.bulgeRadius > t.radius + 0.5f * t.spacing)) {
    throw std::invalid_argument("fusiform aneurysm: the bulge radius must exceed the tube's radius by at least half a spacing");
  }
  if (!positive(a.bulgeLength) || a.bulgeLength < 4.0f * t.spacing) {
    throw std::invalid_argument("fusiform aneurysm: the bulge must be at least four spacings long");
  }
  if (double(a.bulgeLength) + 2.0 * (t.layers + 1.0) * t.spacing > t.length) {
    throw std::invalid_argument("fusiform aneurysm: the tube must be longer than the bulge plus its wall on both sides");
  }
  if (!positive(a.sacStiffnessScale) || !positive(a.sacStrengthScale)) {
    throw std::invalid_argument("fusiform aneurysm: the bulge's stiffness and strength scales must be positive");
  }
}

}  // namespace

FusiformBuild buildFusiformAneurysm(const AneurysmSpec& a) {
  buildTube(a.tube);  // checks the tube's own parameters
  check(a);
  const TubeSpec& t = a.tube;
  const double dp = t.spacing, x0 = t.x0, L = t.length, xc = x0 + 0.5 * L;
  const double cy = t.centreYZ.x, cz = t.centreYZ.y;

  // Rings at equal arc length along the inner layer's profile r0(x) = r(x) + dp / 2.
  const int samples = 20000;
  std::vector<double> arc(samples + 1, 0.0);
  for (int k = 1; k <= samples; ++k) {
    const double xa = x0 + L * (k - 1) / samples, xb = x0 + L * k / samples;
    const double dr = innerRadiusAt(a, xb) - innerRadiusAt(a, xa);
    arc[k] = arc[k - 1] + std::hypot(xb - xa, dr);
  }
  const auto rings = static_cast<std::uint32_t>(std::max(3L, std::lround(arc.back() / dp)));
  std::vector<double> ringX(rings);
  for (std::uint32_t i = 0; i < rings; ++i) {
    const double target = (i + 0.5) * arc.back() / rings;
    const auto it = std::lower_bound(arc.begin(), arc.end(), target);
    const auto k = std::max<std::ptrdiff_t>(1, it - arc.begin());
    const double f = (target - arc[k - 1]) / std::max(arc[k] - arc[k - 1], 1e-300);
    ringX[i] = x0 + L * (double(k - 1) + f) / samples;
  }

  FusiformBuild b;
  std::vector<glm::dvec3> pos, inward;
  std::vector<std::uint32_t> layerOf;
  std::vector<std::uint8_t> anchored;
  for (std::uint32_t l = 0; l < t.layers; ++l)
    for (std::uint32_t i = 0; i < rings; ++i) {
      const double x = ringX[i], r = innerRadiusAt(a, x) + (l + 0.5) * dp;
      const auto around = static_cast<std::uint32_t>(std::max(8L, std::lround(2.0 * std::numbers::pi * r / dp)));
      for (std::uint32_t k = 0; k < around; ++k) {
        const double theta = 2.0 * std::numbers::pi * (k + 0.5 * (i % 2)) / around;
        pos.emplace_back(x, cy + r * std::cos(theta), cz + r * std::sin(theta));
        inward.push_back(-outwardNormal(a, x, theta));
        layerOf.push_back(l);
        anchored.push_back(!t.periodic && t.anchorEnds && (i == 0 || i + 1 == rings));
        b.inBulge.push_back(std::abs(x - xc) < 0.5 * a.bulgeLength);
      }
    }
  b.wall = static_cast<std::uint32_t>(pos.size());
  auto separation = [&](const glm::dvec3& p, const glm::dvec3& q) {
    glm::dvec3 d = q - p;
    if (t.periodic) d.x -= L * std::round(d.x / L);
    return d;
  };

  sim::SpringNetwork& net = b.network;
  std::vector<std::vector<std::uint32_t>> adjacent(b.wall);
  const float bulgeK = t.stiffness * a.sacStiffnessScale, bulgeF = t.maxForce * a.sacStrengthScale;
  for (std::uint32_t i = 0; i < b.wall; ++i)
    for (std::uint32_t j = i + 1; j < b.wall; ++j) {
      const double length = glm::length(separation(pos[i], pos[j]));
      if (length >= kLinkRadius * dp) continue;
      const bool bulge = b.inBulge[i] || b.inBulge[j];
      linkSpring(net, adjacent, {i, j, float(length), bulge ? bulgeK : t.stiffness, t.damping, bulge ? bulgeF : t.maxForce});
    }
  net.points.resize(b.wall);
  for (std::uint32_t i = 0; i < b.wall; ++i) {
    sim::WallPoint& w = net.points[i];
    w.mass = t.pointMass;
    w.anchored = anchored[i] != 0;
    double best = 0.5;  // at least sin(30 deg) along the normal, else keep the built normal
    for (std::uint32_t pa : adjacent[i])
      for (std::uint32_t pb : adjacent[i]) {
        if (pa == pb || layerOf[pa] != layerOf[i] || layerOf[pb] != layerOf[i]) continue;
        const glm::dvec3 ea = separation(pos[i], pos[pa]), eb = separation(pos[i], pos[pb]);
        const double score = glm::dot(glm::cross(ea, eb), inward[i]) / (glm::length(ea) * glm::length(eb));
        if (score > best) best = score, w.frameA = pa, w.frameB = pb;
      }
  }

  // The bulge's inner area: the surface of revolution of r(x) over |x - xc| < Lb / 2.
  for (int k = 0; k < samples; ++k) {
    const double x = x0 + L * (k + 0.5) / samples;
    if (std::abs(x - xc) >= 0.5 * a.bulgeLength) continue;
    const double s = slopeAt(a, x);
    b.bulgeInnerArea += 2.0 * std::numbers::pi * innerRadiusAt(a, x) * std::sqrt(1.0 + s * s) * (L / samples);
  }

  ParticleSet& set = b.particles;
  for (std::uint32_t i = 0; i < b.wall; ++i) set.add(glm::vec3(pos[i]), t.fluidMass, float(HEMO_KIND_WALL), glm::vec3(inward[i]));
  const auto slices = static_cast<std::uint32_t>(std::max(1L, std::lround(L / dp)));
  const double dx = L / slices;
  for (std::uint32_t j = 0; j < slices; ++j) {
    const double x = x0 + (j + 0.5) * dx, R = innerRadiusAt(a, x);
    const auto K = static_cast<std::uint32_t>(std::max(1L, std::lround(R / dp)));
    const double dr = R / K;
    for (std::uint32_t k = 0; k < K; ++k) {
      const double r = (k + 0.5) * dr;
      const auto count = static_cast<std::uint32_t>(std::max(1L, std::lround(2.0 * std::numbers::pi * r / dr)));
      for (std::uint32_t m = 0; m < count; ++m) {
        const double theta = 2.0 * std::numbers::pi * (m + 0.5 * (j % 2)) / count;
        const glm::dvec3 p(x, cy + r * std::cos(theta), cz + r * std::sin(theta));
        bool clear = true;
        for (std::uint32_t w = 0; w < b.wall && clear; ++w) clear = glm::length(separation(p, pos[w])) >= kFluidClearance * dp;
        if (clear) set.add(glm::vec3(p), t.fluidMass, float(HEMO_KIND_FLUID));
      }
    }
  }
  set.fluid = set.size() - b.wall;
  set.boundary = 0;
  set.numberIds();
  net.validate();
  return b;
}

}  // namespace hemo::scene
