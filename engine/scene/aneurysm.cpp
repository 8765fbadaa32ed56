#include "hemo/scene/aneurysm.hpp"
#include "hemo/scene/mesh_vessel.hpp"

#include "hemo/scene/bifurcation.hpp"

#include "interface/sph.h"
#include "wall_links.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <set>
#include <stdexcept>
#include <string>

namespace hemo::scene {

namespace {

// Springs join sac points to every wall point nearer than this many spacings: the six
// nearest neighbours of a Fibonacci sphere (about 1.07 dp away, the next ring at ~1.9 dp) and
// the nearest points of the next layer.
constexpr double kSacLinkRadius = 1.5;
// Sac points nearer than this many spacings to a kept tube point are dropped (the surfaces
// overlap at the neck).
constexpr double kMergeRadius = 0.6;
// No fluid particle starts nearer than this many spacings to a wall point.
constexpr double kFluidClearance = 0.8;
constexpr std::uint32_t kDropped = 0xffffffffu;

glm::dvec3 centreOf(const AneurysmSpec& a) {
  const double d = sacCentreOffset(a.tube.radius, a.sacRadius, a.neckWidth);
  return {double(a.tube.x0) + 0.5 * a.tube.length, a.tube.centreYZ.x, double(a.tube.centreYZ.y) + d};
}

double axisDistance(const TubeSpec& t, glm::dvec3 p) { return std::hypot(p.y - t.centreYZ.x, p.z - t.centreYZ.y); }

void check(const AneurysmSpec& a) {
  const TubeSpec& t = a.tube;
  auto positive = [](float v) { return std::isfinite(v) && v > 0.0f; };
  if (!positive(a.sacRadius)) throw std::invalid_argument("aneurysm: the sac radius must be positive (m)");
  if (!positive(a.neckWidth)) throw std::invalid_argument("aneurysm: the neck width must be positive (m)");
  if (!positive(a.sacStiffnessScale) || !positive(a.sacStrengthScale)) {
    throw std::invalid_argument("aneurysm: the sac's stiffness and strength scales must be positive");
  }
  if (a.sacRadius < 2.0f * t.spacing) throw std::invalid_argument("aneurysm: the sac radius must be at least two spacings");
  if (a.neckWidth < 2.0f * t.spacing) throw std::invalid_argument("aneurysm: the neck must be at least two spacings wide");
  if (a.neckWidth > 1.8f * t.radius || a.neckWidth > 1.8f * a.sacRadius) {
    throw std::invalid_argument("aneurysm: the neck width must be at most 0.9 x the tube's and the sac's diameters");
  }
  const double reach = double(a.sacRadius) + (t.layers + 1.0) * t.spacing;
  if (2.0 * reach > t.length) {
    throw std::invalid_argument("aneurysm: the tube must be longer than the sac with its wall (length >= " +
                                std::to_string(2.0 * reach) + " m)");
  }
}

}  // namespace

double sacCentreOffset(double R, double Rs, double w) {
  const double hw = 0.5 * w;
  return std::sqrt(R * R - hw * hw) + std::sqrt(Rs * Rs - hw * hw);
}

AneurysmBuild buildSaccularAneurysm(const AneurysmSpec& a) {
  check(a);
  const TubeSpec& t = a.tube;
  TubeBuild tube = buildTube(t);  // checks the tube's own parameters
  const double dp = t.spacing;
  const glm::dvec3 c = centreOf(a);
  const std::uint32_t perLayer = tube.along * tube.around;

  AneurysmBuild b;
  b.sacCentre = glm::vec3(c);
  std::vector<glm::dvec3> pos;
  std::vector<glm::dvec3> inward;
  std::vector<std::uint32_t> layerOf;
  // Tube points outside the sac's sphere of the same layer.
  std::vector<std::uint32_t> remap(tube.wall, kDropped);
  for (std::uint32_t i = 0; i < tube.wall; ++i) {
    const glm::dvec3 p(tube.particles.positions[i]);
    const std::uint32_t l = i / perLayer;
    if (glm::length(p - c) < a.sacRadius + (l + 0.5) * dp) continue;
    remap[i] = std::uint32_t(pos.size());
    pos.push_back(p);
    inward.push_back(glm::dvec3(tube.particles.normals[i]));
    layerOf.push_back(l);
    b.inSac.push_back(0);
  }
  const auto tubeKept = std::uint32_t(pos.size());
  // Sac points: a Fibonacci sphere per layer, outside the tube's cylinder of that layer and
  // clear of the kept tube points.
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
  std::uint32_t innerAll = 0, innerKept = 0;
  for (std::uint32_t l = 0; l < t.layers; ++l) {
    const double S = a.sacRadius + (l + 0.5) * dp;
    const double Rl = t.radius + (l + 0.5) * dp;
    const auto count = static_cast<std::uint32_t>(std::lround(4.0 * std::numbers::pi * S * S / (dp * dp)));
    for (std::uint32_t k = 0; k < count; ++k) {
      const double z = 1.0 - (2.0 * k + 1.0) / count;
      const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
      const double phi = golden * k;
      const glm::dvec3 dir(r * std::cos(phi), r * std::sin(phi), z);
      const glm::dvec3 p = c + S * dir;
      if (l == 0) ++innerAll;
      if (axisDistance(t, p) < Rl) continue;
      bool clash = false;
      for (std::uint32_t j = 0; j < tubeKept && !clash; ++j) clash = glm::length(pos[j] - p) < kMergeRadius * dp;
      if (clash) continue;
      if (l == 0) ++innerKept;
      pos.push_back(p);
      inward.push_back(-dir);
      layerOf.push_back(l);
      b.inSac.push_back(1);
    }
  }
  b.sacInnerArea = 4.0 * std::numbers::pi * double(a.sacRadius) * a.sacRadius * innerKept / std::max(innerAll, 1u);
  b.wall = static_cast<std::uint32_t>(pos.size());

  // Springs: the tube's between kept points, then each sac point to its near wall points.
  sim::SpringNetwork& net = b.network;
  std::vector<std::vector<std::uint32_t>> adjacent(b.wall);
  auto add = [&](const sim::Spring& s) { linkSpring(net, adjacent, s); };
  for (const sim::Spring& s : tube.network.springs) {
    if (remap[s.a] == kDropped || remap[s.b] == kDropped) continue;
    add({remap[s.a], remap[s.b], s.restLength, s.stiffness, s.damping, s.maxForce});
  }
  const float sacK = t.stiffness * a.sacStiffnessScale, sacF = t.maxForce * a.sacStrengthScale;
  for (std::uint32_t i = tubeKept; i < b.wall; ++i)
    for (std::uint32_t j = 0; j < i; ++j) {
      const double length = glm::length(pos[i] - pos[j]);
      if (length < kSacLinkRadius * dp) add({j, i, float(length), sacK, t.damping, sacF});
    }

  // Points: tube points keep their frames where both frame points were kept; the others take
  // the pair of same-layer neighbours whose cross product best follows the inward normal.
  net.points.resize(b.wall);
  for (std::uint32_t i = 0; i < tube.wall; ++i) {
    if (remap[i] == kDropped) continue;
    const sim::WallPoint& w = tube.network.points[i];
    sim::WallPoint& out = net.points[remap[i]];
    out = w;
    out.frameA = out.frameB = sim::WallPoint::kNoFrame;
    if (w.frameA != sim::WallPoint::kNoFrame && remap[w.frameA] != kDropped && remap[w.frameB] != kDropped) {
      out.frameA = remap[w.frameA];
      out.frameB = remap[w.frameB];
    }
  }
  for (std::uint32_t i = 0; i < b.wall; ++i) {
    sim::WallPoint& w = net.points[i];
    if (i >= tubeKept) w.mass = t.pointMass;
    if (w.frameA != sim::WallPoint::kNoFrame) continue;
    double best = 0.5;  // at least sin(30 deg) along the normal, else keep the built normal
    for (std::uint32_t pa : adjacent[i])
      for (std::uint32_t pb : adjacent[i]) {
        if (pa == pb || layerOf[pa] != layerOf[i] || layerOf[pb] != layerOf[i]) continue;
        const glm::dvec3 ea = pos[pa] - pos[i], eb = pos[pb] - pos[i];
        const double score = glm::dot(glm::cross(ea, eb), inward[i]) / (glm::length(ea) * glm::length(eb));
        if (score > best) best = score, w.frameA = pa, w.frameB = pb;
      }
  }

  // Particles: the wall, then the fluid: the tube's rings (tubeFluidPoints) and, outside the
  // tube's lumen, concentric Fibonacci shells about the sac's centre at radii (k + 1/2) dr
  // (dr = Rs / round(Rs / dp), round(4 pi r^2 / dr^2) points each, one per dr^3 of the shell
  // they stand for), the outer one a spacing inside the sac's first layer. Fluid points
  // nearer than kFluidClearance spacings to a wall point are dropped (at the neck's rim),
  // and shell points that crowd a ring point at the lumen's edge.
  ParticleSet& set = b.particles;
  for (std::uint32_t i = 0; i < b.wall; ++i) set.add(glm::vec3(pos[i]), t.fluidMass, float(HEMO_KIND_WALL), glm::vec3(inward[i]));
  auto clearOfWall = [&](const glm::dvec3& p) {
    for (std::uint32_t w = 0; w < b.wall; ++w) {
      if (glm::length(pos[w] - p) < kFluidClearance * dp) return false;
    }
    return true;
  };
  std::vector<glm::dvec3> fluid;
  for (const glm::dvec3& p : tubeFluidPoints(t, tube.along)) {
    if (clearOfWall(p)) fluid.push_back(p);
  }
  const std::size_t ringPoints = fluid.size();
  const auto shells = static_cast<std::uint32_t>(std::max(1L, std::lround(a.sacRadius / dp)));
  const double dr = double(a.sacRadius) / shells;
  for (std::uint32_t k = 0; k < shells; ++k) {
    const double S = (k + 0.5) * dr;
    const auto count = static_cast<std::uint32_t>(std::max(1L, std::lround(4.0 * std::numbers::pi * S * S / (dr * dr))));
    for (std::uint32_t m = 0; m < count; ++m) {
      const double z = 1.0 - (2.0 * m + 1.0) / count;
      const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
      const double phi = golden * m + k;  // each shell turned, so shells do not line up
      const glm::dvec3 p = c + S * glm::dvec3(r * std::cos(phi), r * std::sin(phi), z);
      if (axisDistance(t, p) < t.radius || !clearOfWall(p)) continue;
      bool crowded = false;
      for (std::size_t j = 0; j < ringPoints && !crowded; ++j) crowded = glm::length(fluid[j] - p) < kFluidClearance * dp;
      if (!crowded) fluid.push_back(p);
    }
  }
  for (const glm::dvec3& p : fluid) set.add(glm::vec3(p), t.fluidMass, float(HEMO_KIND_FLUID));
  set.fluid = set.size() - b.wall;
  set.boundary = 0;
  set.numberIds();
  net.validate();
  return b;
}

double innerRadiusAt(const AneurysmSpec& a, double x) {
  const TubeSpec& t = a.tube;
  if (!(a.bulgeRadius > 0.0f) || !(a.bulgeLength > 0.0f)) return t.radius;
  const double u = (x - (double(t.x0) + 0.5 * t.length)) / a.bulgeLength;
  if (std::abs(u) >= 0.5) return t.radius;
  const double c = std::cos(std::numbers::pi * u);
  return t.radius + (double(a.bulgeRadius) - t.radius) * c * c;
}

bool outsideVessel(const AneurysmSpec& a, glm::vec3 point, float margin) {
  const TubeSpec& t = a.tube;
  const glm::dvec3 p(point);
  const double wall = double(t.layers) * t.spacing + margin;
  if (a.mesh) return !a.mesh->inside(p) && !(a.mesh->distance(p, wall) < wall);
  if (a.branchLength > 0.0f) return bifurcationDistance(bifurcationGeometry(a), p, double(t.radius) + wall) > 0.0;
  if (!t.periodic && (p.x < t.x0 || p.x > double(t.x0) + t.length)) return true;
  if (axisDistance(t, p) <= innerRadiusAt(a, p.x) + wall) return false;
  return a.sacRadius <= 0.0f || glm::length(p - centreOf(a)) > a.sacRadius + wall;
}

double sacRupturePressure(const AneurysmBuild& b) {
  const glm::dvec3 c(b.sacCentre);
  const auto& pos = b.particles.positions;
  double sumKg2 = 0.0, uStar = std::numeric_limits<double>::infinity();
  for (const sim::Spring& s : b.network.springs) {
    if (!b.inSac[s.a] || !b.inSac[s.b]) continue;
    const glm::dvec3 pa(pos[s.a]), pb(pos[s.b]);
    const double g = glm::dot(glm::normalize(pb - pa), glm::normalize(pb - c) - glm::normalize(pa - c));  // dL/du
    sumKg2 += double(s.stiffness) * g * g;
    if (g > 1e-9 && s.stiffness > 0.0f) uStar = std::min(uStar, double(s.maxForce) / (double(s.stiffness) * g));
  }
  if (!std::isfinite(uStar) || sumKg2 <= 0.0 || b.sacInnerArea <= 0.0) {
    throw std::invalid_argument("aneurysm: no sac spring stretches when the sac widens");
  }
  return uStar * sumKg2 / b.sacInnerArea;
}

}  // namespace hemo::scene
