#include "hemo/scene/bifurcation.hpp"

#include "interface/sph.h"
#include "point_bins.hpp"
#include "wall_links.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <unordered_map>

namespace hemo::scene {

namespace {

constexpr double kLinkRadius = 1.5;      // spacings: springs join wall points nearer than this
constexpr double kMergeRadius = 0.6;     // spacings: a wall point this near a kept one of its layer is dropped
constexpr double kFillRadius = 0.7;      // spacings: the seams are filled until no point of a layer's surface is farther from its points
constexpr double kFluidClearance = 0.8;  // spacings: no fluid this near a wall point or a kept fluid point
// The element an element's mirror image across the x-z plane through the axis belongs to
// (segments: parent, split -> +bend, +bend -> merge, split -> -bend, -bend -> merge; then
// the joints split, +bend, merge, -bend).
constexpr std::uint8_t kMirrorElement[9] = {0, 3, 4, 1, 2, 5, 8, 7, 6};
constexpr double kGolden = std::numbers::pi * (3.0 - 2.2360679774997896964);  // Fibonacci sphere's turn

// Distance from p to the segment's axis (clamped to its ends: the capsule's distance), over
// the periodic images along x.
double capsuleDistance(const BifurcationGeometry::Segment& s, glm::dvec3 p, double period) {
  const glm::dvec3 d = s.b - s.a;
  const double len2 = glm::dot(d, d);
  double best = std::numeric_limits<double>::infinity();
  for (int k = -1; k <= 1; ++k) {
    const glm::dvec3 q = p + glm::dvec3(k * period, 0.0, 0.0);
    const double t = std::clamp(glm::dot(q - s.a, d) / len2, 0.0, 1.0);
    best = std::min(best, glm::length(q - (s.a + t * d)));
  }
  return best;
}

// A segment's start, length, unit direction and two unit vectors across it (the first +z:
// every leg lies in the x-y plane).
struct LegFrame {
  glm::dvec3 a, d, e1, e2;
  double length;
};
LegFrame legFrame(const BifurcationGeometry::Segment& s) {
  LegFrame f;
  f.a = s.a;
  f.length = glm::length(s.b - s.a);
  f.d = (s.b - s.a) / f.length;
  f.e1 = glm::dvec3(0.0, 0.0, 1.0);
  f.e2 = glm::normalize(glm::cross(f.d, f.e1));
  return f;
}

}  // namespace

BifurcationGeometry bifurcationGeometry(const AneurysmSpec& a) {
  const TubeSpec& t = a.tube;
  if (!t.periodic && !a.openEnds) {
    throw std::invalid_argument("bifurcation: the tube must be periodic along x (the merged flow returns through the seam) or have open ends");
  }
  const double theta = a.branchAngle, len = a.branchLength, dp = t.spacing, L = t.length;
  if (!std::isfinite(theta) || !(theta > 0.0) || theta > 80.0 * std::numbers::pi / 180.0 + 1e-9) {
    throw std::invalid_argument("bifurcation: the branch angle must be in (0, 80] degrees");
  }
  const double outer = double(t.radius) + t.layers * dp;
  if (!std::isfinite(len) || 2.0 * len * std::sin(theta) < (2.0 * outer + dp) * (1.0 - 1e-6)) {
    throw std::invalid_argument("bifurcation: the branches must be long enough to part at the bends: 2 L sin(angle) >= 2 (R + layers dp) + dp = " +
                                std::to_string(2.0 * outer + dp) + " m (it is " + std::to_string(2.0 * len * std::sin(theta)) + " m)");
  }
  const double span = 2.0 * len * std::cos(theta);
  if (L - span < 4.0 * dp) {
    throw std::invalid_argument("bifurcation: the tube must be longer than the loop (2 L cos(angle) = " + std::to_string(span) +
                                " m) by at least four spacings");
  }
  BifurcationGeometry g;
  g.period = L;
  const glm::dvec3 split(double(t.x0) + 0.5 * (L - span), t.centreYZ.x, t.centreYZ.y);
  const glm::dvec3 merge = split + glm::dvec3(span, 0.0, 0.0);
  const glm::dvec3 up = split + len * glm::dvec3(std::cos(theta), std::sin(theta), 0.0);
  const glm::dvec3 down = split + len * glm::dvec3(std::cos(theta), -std::sin(theta), 0.0);
  g.segments = {{merge, split + glm::dvec3(L, 0.0, 0.0)}, {split, up}, {up, merge}, {split, down}, {down, merge}};
  g.joints = {split, up, merge, down};
  return g;
}

double bifurcationDistance(const BifurcationGeometry& g, glm::dvec3 p, double radius) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& s : g.segments) best = std::min(best, capsuleDistance(s, p, g.period));
  return best - radius;
}

BifurcationBuild buildBifurcation(const AneurysmSpec& a) {
  buildTube(a.tube);  // checks the tube's own parameters
  const TubeSpec& t = a.tube;
  BifurcationBuild b;
  b.geometry = bifurcationGeometry(a);
  const BifurcationGeometry& g = b.geometry;
  const double dp = t.spacing, L = t.length, x0 = t.x0, R = t.radius;
  auto wrap = [&](glm::dvec3 p) {
    p.x -= L * std::floor((p.x - x0) / L);
    return p;
  };
  // Open ends: the same vessel cut at the seam, its parent starting at x0 and ending at x0 + L;
  // nothing links across the cut (the bins are not periodic), and the wall points within a
  // spacing of either end are anchored (the vessel goes on beyond its cut, as the tube's end
  // rings).
  const double binPeriod = a.openEnds ? 1e3 * L : L;
  auto inside = [&](glm::dvec3 p, double r) { return bifurcationDistance(g, p, r) < -1e-6 * dp; };
  const double cy = t.centreYZ.x;
  auto mirror = [&](glm::dvec3 p) { return glm::dvec3(p.x, 2.0 * cy - p.y, p.z); };

  // Wall candidates per layer: the legs' rings, then the joints' spheres.
  std::vector<glm::dvec3> pos, inward;
  std::vector<std::uint32_t> mirrorOf;  // each wall point's mirror image (itself on the plane)
  Bins wallBins(x0, binPeriod, kLinkRadius * dp);
  for (std::uint32_t l = 0; l < t.layers; ++l) {
    const double r = R + (l + 0.5) * dp;
    Bins layerBins(x0, binPeriod, kLinkRadius * dp);
    auto keep = [&](glm::dvec3 p, glm::dvec3 in, std::uint8_t element) {
      const auto id = std::uint32_t(pos.size());
      layerBins.add(p, id);
      wallBins.add(p, id);
      pos.push_back(p);
      inward.push_back(in);
      b.element.push_back(element);
      b.layer.push_back(std::uint8_t(l));
    };
    // The wall is mirror-symmetric across the x-z plane through the axis (an asymmetric
    // sampling started the loop with a circulation that sent three times as much flow through
    // one branch as through the other for the whole run: a loop's circulation decays only on
    // the viscous time R^2 / nu, about a second). Candidates come from the upper half (the
    // parent, the upper legs, the split, the upper bend, the merge); one that is accepted is
    // kept with its mirror image. A candidate nearer the plane than half the merge radius
    // would crowd its own image: it moves onto the plane, along z on its element's surface,
    // and is kept alone. `merge` (spacings): no two points of a layer nearer than this.
    auto offer = [&](glm::dvec3 p, glm::dvec3 in, std::uint8_t element, double merge) {
      const bool single = std::abs(p.y - cy) < 0.5 * merge * dp;
      if (single) {
        // On the plane y = cy: (x - c.x)^2 + (z - c.z)^2 + ... = r^2 for the element's axis
        // (a segment in the x-y plane) or centre (a joint).
        double reach2;
        glm::dvec3 centre;
        if (element < 5) {
          const auto& seg = g.segments[element];
          const glm::dvec3 d = glm::normalize(seg.b - seg.a);
          const glm::dvec3 q(p.x - seg.a.x, cy - seg.a.y, 0.0);
          reach2 = r * r - (q.x * q.x + q.y * q.y) + std::pow(q.x * d.x + q.y * d.y, 2.0);
          centre = seg.a;
        } else {
          centre = g.joints[element - 5];
          reach2 = r * r - std::pow(p.x - centre.x, 2.0) - std::pow(cy - centre.y, 2.0);
        }
        if (!(reach2 >= 0.0)) return;
        p = glm::dvec3(p.x, cy, centre.z + std::copysign(std::sqrt(reach2), p.z - centre.z));
        if (element < 5) {
          const auto& seg = g.segments[element];
          const glm::dvec3 d = glm::normalize(seg.b - seg.a), q = p - seg.a;
          in = -glm::normalize(q - glm::dot(q, d) * d);
        } else {
          in = -glm::normalize(p - centre);
        }
      }
      if (inside(p, r)) return;
      p = wrap(p);
      bool crowded = false;
      layerBins.near(p, merge * dp, [&](std::uint32_t, glm::dvec3) { crowded = true; });
      if (crowded) return;
      const auto id = std::uint32_t(pos.size());
      if (single) {
        in.y = 0.0;  // on the plane: a mirror-invariant normal
        in = glm::normalize(in);
        keep(p, in, element);
        mirrorOf.push_back(id);
      } else {
        keep(p, in, element);
        keep(mirror(p), glm::dvec3(in.x, -in.y, in.z), kMirrorElement[element]);
        mirrorOf.push_back(id + 1);
        mirrorOf.push_back(id);
      }
    };
    for (std::size_t e = 0; e < 3; ++e) {
      const LegFrame f = legFrame(g.segments[e]);
      const auto rings = std::max(1L, std::lround(f.length / dp));
      const auto around = std::max(8L, std::lround(2.0 * std::numbers::pi * r / dp));
      for (long i = 0; i < rings; ++i)
        for (long k = 0; k < around; ++k) {
          const double phi = 2.0 * std::numbers::pi * (k + 0.5 * (i % 2)) / around;
          const glm::dvec3 radial = std::cos(phi) * f.e1 + std::sin(phi) * f.e2;
          offer(f.a + (i + 0.5) * f.length / rings * f.d + r * radial, -radial, std::uint8_t(e), kMergeRadius);
        }
    }
    const auto count = std::max(8L, std::lround(4.0 * std::numbers::pi * r * r / (dp * dp)));
    for (std::size_t j = 0; j < 3; ++j)
      for (long k = 0; k < count; ++k) {
        const double z = 1.0 - (2.0 * k + 1.0) / count, rho = std::sqrt(std::max(0.0, 1.0 - z * z));
        const double phi = kGolden * k;
        const glm::dvec3 dir(rho * std::cos(phi), rho * std::sin(phi), z);
        offer(g.joints[j] + r * dir, -dir, std::uint8_t(g.segments.size() + j), kMergeRadius);
      }
    // Seams: where two elements cut each other, each loses its points inside the other and
    // the last kept rows can be a spacing apart across the seam. Samples of the layer's
    // surface every quarter spacing that are farther than kFillRadius dp from every kept
    // point become wall points too (greedily, in sample order).
    for (std::size_t e = 0; e < 3; ++e) {
      const LegFrame f = legFrame(g.segments[e]);
      const auto steps = std::max(1L, std::lround(4.0 * f.length / dp));
      const auto around = std::max(32L, std::lround(8.0 * std::numbers::pi * r / dp));
      for (long i = 0; i <= steps; ++i)
        for (long k = 0; k < around; ++k) {
          const double phi = 2.0 * std::numbers::pi * k / around;
          const glm::dvec3 radial = std::cos(phi) * f.e1 + std::sin(phi) * f.e2;
          offer(f.a + (double(i) * f.length / steps) * f.d + r * radial, -radial, std::uint8_t(e), kFillRadius);
        }
    }
  }
  b.wall = static_cast<std::uint32_t>(pos.size());

  // Springs between every pair of wall points nearer than kLinkRadius dp (in id order).
  sim::SpringNetwork& net = b.network;
  std::vector<std::vector<std::uint32_t>> adjacent(b.wall);
  for (std::uint32_t i = 0; i < b.wall; ++i) {
    std::vector<std::pair<std::uint32_t, double>> near;
    wallBins.near(pos[i], kLinkRadius * dp, [&](std::uint32_t j, glm::dvec3 d) {
      if (j > i) near.emplace_back(j, glm::length(d));
    });
    std::sort(near.begin(), near.end());
    for (const auto& [j, length] : near) {
      linkSpring(net, adjacent, {i, j, float(length), t.stiffness, t.damping, t.maxForce});
    }
  }
  // Frames: the pair of same-layer spring neighbours whose cross product best follows the
  // inward normal, chosen for the first point of each mirror pair; its image takes the images
  // of the pair in the other order (a reflection turns the cross product's sense), so the
  // normals the GPU computes from the frames stay mirror images. A point on the plane takes a
  // neighbour and its image (their cross product lies in the plane).
  net.points.resize(b.wall);
  for (std::uint32_t i = 0; i < b.wall; ++i) {
    sim::WallPoint& w = net.points[i];
    w.mass = t.pointMass;
    w.anchored = a.openEnds && (pos[i].x - x0 < dp || x0 + L - pos[i].x < dp);
    if (mirrorOf[i] < i) continue;  // the image of a point already framed
    const bool onPlane = mirrorOf[i] == i;
    // At least sin(30 deg) along the normal (else the point keeps its built normal); on the
    // plane, where only mirror pairs qualify, any pair on the inward side.
    double best = onPlane ? 0.0 : 0.5;
    for (std::uint32_t pa : adjacent[i])
      for (std::uint32_t pb : adjacent[i]) {
        if (pa == pb || b.layer[pa] != b.layer[i] || b.layer[pb] != b.layer[i]) continue;
        if (onPlane && pb != mirrorOf[pa]) continue;
        const glm::dvec3 ea = wallBins.separation(pos[i], pos[pa]), eb = wallBins.separation(pos[i], pos[pb]);
        const double score = glm::dot(glm::cross(ea, eb), inward[i]) / (glm::length(ea) * glm::length(eb));
        if (score > best) best = score, w.frameA = pa, w.frameB = pb;
      }
    if (!onPlane && w.frameA != sim::WallPoint::kNoFrame) {
      sim::WallPoint& image = net.points[mirrorOf[i]];
      image.frameA = mirrorOf[w.frameB];
      image.frameB = mirrorOf[w.frameA];
    }
  }

  // Fluid: rings per slice along every leg, then shells about every joint.
  ParticleSet& set = b.particles;
  for (std::uint32_t i = 0; i < b.wall; ++i) set.add(glm::vec3(pos[i]), t.fluidMass, float(HEMO_KIND_WALL), glm::vec3(inward[i]));
  Bins fluidBins(x0, binPeriod, kLinkRadius * dp);
  std::uint32_t fluid = 0;
  // Mirror-symmetric as the wall: candidates from the upper half, each kept with its image,
  // those nearer the plane than half the clearance moved onto it and kept alone.
  auto offerFluid = [&](glm::dvec3 p) {
    const bool single = std::abs(p.y - cy) < 0.5 * kFluidClearance * dp;
    if (single) p.y = cy;
    if (!(bifurcationDistance(g, p, R) < 0.0)) return;
    p = wrap(p);
    bool crowded = false;
    auto hit = [&](std::uint32_t, glm::dvec3) { crowded = true; };
    wallBins.near(p, kFluidClearance * dp, hit);
    if (!crowded) fluidBins.near(p, kFluidClearance * dp, hit);
    if (crowded) return;
    for (const glm::dvec3& q : {p, mirror(p)}) {
      fluidBins.add(q, fluid++);
      set.add(glm::vec3(q), t.fluidMass, float(HEMO_KIND_FLUID));
      if (single) break;
    }
  };
  // Each leg fills its own part of the lumen (slices overlapping at the joints started the
  // fluid 14% dense there, and the bends' outer wedges 25% thin): the parts meet at the miter
  // planes of the joints (normal d_in + d_out) and, for the upper legs, at the mirror plane.
  // Its slices run on past the leg's ends into the wedges, clipped by the miters and the lumen.
  const glm::dvec3 xAxis(1.0, 0.0, 0.0), yAxis(0.0, 1.0, 0.0);
  const glm::dvec3 up = glm::normalize(g.segments[1].b - g.segments[1].a), down = glm::normalize(g.segments[2].b - g.segments[2].a);
  const glm::dvec3 splitMiter = glm::normalize(xAxis + up), mergeMiter = glm::normalize(down + xAxis);
  struct Cut {
    glm::dvec3 at, normal;  // keeps dot(p - at, normal) >= -slack
    double slack = 0.0;     // m: the mirror plane's lets in what offerFluid moves onto it
  };
  const Cut mirrorPlane{glm::dvec3(0.0, cy, 0.0), yAxis, 0.5 * kFluidClearance * dp};
  const std::vector<Cut> cuts[3] = {
      {{g.joints[2], mergeMiter}, {g.joints[0] + L * xAxis, -splitMiter}},
      {{g.joints[0], splitMiter}, {g.joints[1], -xAxis}, mirrorPlane},
      {{g.joints[1], xAxis}, {g.joints[2], -mergeMiter}, mirrorPlane}};
  const auto K = std::max(1L, std::lround(R / dp));
  const double dr = R / K;
  const double overhang = R * std::tan(std::min(double(a.branchAngle), 1.4)) + dp;
  for (std::size_t e = 0; e < 3; ++e) {
    const LegFrame f = legFrame(g.segments[e]);
    const auto slices = std::max(1L, std::lround(f.length / dp));
    const long extra = static_cast<long>(std::ceil(overhang / (f.length / slices)));
    for (long j = -extra; j < slices + extra; ++j)
      for (long k = 0; k < K; ++k) {
        const double r = (k + 0.5) * dr;
        const auto count = std::max(1L, std::lround(2.0 * std::numbers::pi * r / dr));
        for (long m = 0; m < count; ++m) {
          const double phi = 2.0 * std::numbers::pi * (m + 0.5 * ((j + extra) % 2)) / count;
          const glm::dvec3 p = f.a + (j + 0.5) * f.length / slices * f.d + r * (std::cos(phi) * f.e1 + std::sin(phi) * f.e2);
          bool mine = true;
          for (const Cut& c : cuts[e]) mine = mine && glm::dot(p - c.at, c.normal) >= -c.slack;
          if (mine) offerFluid(p);
        }
      }
  }
  // Whatever gaps are left (the rounded outer side of the bends): shells about the joints.
  for (std::size_t j = 0; j < 3; ++j)
    for (long k = 0; k < K; ++k) {
      const glm::dvec3 c = g.joints[j];
      const double S = (k + 0.5) * dr;
      const auto count = std::max(1L, std::lround(4.0 * std::numbers::pi * S * S / (dr * dr)));
      for (long m = 0; m < count; ++m) {
        const double z = 1.0 - (2.0 * m + 1.0) / count, rho = std::sqrt(std::max(0.0, 1.0 - z * z));
        const double phi = kGolden * m + k;
        offerFluid(c + S * glm::dvec3(rho * std::cos(phi), rho * std::sin(phi), z));
      }
    }
  set.fluid = fluid;
  set.boundary = 0;
  set.numberIds();
  net.validate();
  return b;
}

}  // namespace hemo::scene
