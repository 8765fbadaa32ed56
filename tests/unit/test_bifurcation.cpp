// The bifurcation builder (a parent tube splitting into two branches that merge again).
#include "hemo/scene/bifurcation.hpp"
#include "hemo/scene/build.hpp"
#include "artery_spec.hpp"
#include "scene_errors.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <nlohmann/json.hpp>

namespace hemo::scene {
namespace {

// R = 4 dp, branches 14 dp long at 30 degrees, in a periodic tube 36 dp long.
AneurysmSpec spec() {
  AneurysmSpec a;
  a.tube = arteryTube(36);
  a.tube.radius = 4 * a.tube.spacing;
  a.branchAngle = float(std::numbers::pi / 6.0);
  a.branchLength = 14 * a.tube.spacing;
  return a;
}

// Inward unit normal of the union's surface at p (radius r), by central differences.
glm::dvec3 inwardNormal(const BifurcationGeometry& g, glm::dvec3 p, double r, double step) {
  glm::dvec3 grad;
  for (int k = 0; k < 3; ++k) {
    glm::dvec3 e(0.0);
    e[k] = step;
    grad[k] = bifurcationDistance(g, p + e, r) - bifurcationDistance(g, p - e, r);
  }
  return -glm::normalize(grad);
}

TEST(Bifurcation, GeometryFollowsTheSpec) {
  const AneurysmSpec a = spec();
  const BifurcationGeometry g = bifurcationGeometry(a);
  const double dp = a.tube.spacing, L = a.tube.length, len = a.branchLength;
  ASSERT_EQ(g.segments.size(), 5u);
  ASSERT_EQ(g.joints.size(), 4u);
  // The loop is centred on the tube; the bends are L sin(theta) off the axis.
  EXPECT_NEAR(0.5 * (g.joints[0].x + g.joints[2].x), a.tube.x0 + 0.5 * L, 1e-12);
  EXPECT_NEAR(g.joints[1].y, len * std::sin(double(a.branchAngle)), 1e-12);
  EXPECT_NEAR(g.joints[3].y, -len * std::sin(double(a.branchAngle)), 1e-12);
  for (std::size_t s = 1; s < 5; ++s) EXPECT_NEAR(glm::length(g.segments[s].b - g.segments[s].a), len, 1e-12);
  // Distances: on the axis -R, across the seam the parent continues, between the legs at the
  // loop's middle the point is outside.
  const double R = a.tube.radius;
  EXPECT_NEAR(bifurcationDistance(g, glm::dvec3(a.tube.x0 + 0.1 * dp, 0.0, 0.0), R), -R, 1e-12);
  EXPECT_NEAR(bifurcationDistance(g, glm::dvec3(a.tube.x0 + L - 0.1 * dp, 0.0, R), R), 0.0, 1e-12);
  EXPECT_GT(bifurcationDistance(g, glm::dvec3(g.joints[1].x, 0.0, 0.0), R), 0.0);
  EXPECT_NEAR(bifurcationDistance(g, g.joints[1] + glm::dvec3(0.0, 0.0, 2.0 * R), R), R, 1e-12);
}

TEST(Bifurcation, WallCoversTheUnionWithoutHoles) {
  const AneurysmSpec a = spec();
  const BifurcationBuild b = buildBifurcation(a);
  const BifurcationGeometry& g = b.geometry;
  const double dp = a.tube.spacing, R = a.tube.radius, L = a.tube.length;
  const auto& x = b.particles.positions;
  auto sep = [&](glm::dvec3 p, glm::dvec3 q) {
    glm::dvec3 d = q - p;
    d.x -= L * std::round(d.x / L);
    return d;
  };
  std::vector<int> springsOf(b.wall, 0);
  for (const auto& s : b.network.springs) {
    ++springsOf[s.a], ++springsOf[s.b];
    EXPECT_NEAR(s.restLength, glm::length(sep(glm::dvec3(x[s.a]), glm::dvec3(x[s.b]))), 1e-4 * dp);
    EXPECT_LT(s.restLength, 1.5 * dp);
  }
  int steepFrames = 0, perElement[9] = {};
  for (std::uint32_t i = 0; i < b.wall; ++i) {
    const glm::dvec3 p(x[i]);
    const double r = R + (b.layer[i] + 0.5) * dp;
    // On the boundary of its layer's union (a point inside another element would be buried).
    EXPECT_NEAR(bifurcationDistance(g, p, r), 0.0, 1e-4 * dp) << "point " << i;
    EXPECT_GE(x[i].x, a.tube.x0);
    EXPECT_LT(x[i].x, a.tube.x0 + L);
    EXPECT_GE(springsOf[i], 4) << "point " << i;
    ++perElement[b.element[i]];
    const auto& w = b.network.points[i];
    ASSERT_NE(w.frameA, sim::WallPoint::kNoFrame) << "point " << i << " has no frame";
    const glm::dvec3 n = glm::normalize(glm::cross(sep(p, glm::dvec3(x[w.frameA])), sep(p, glm::dvec3(x[w.frameB]))));
    // The frame's normal within 60 degrees of the point's inward normal (its element's), and
    // that within 60 degrees of the union's (which, on a seam, is one side's).
    const glm::dvec3 built(b.particles.normals[i]);
    const double along = glm::dot(n, built);
    EXPECT_GT(along, 0.5) << "point " << i << " (element " << int(b.element[i]) << ", y " << p.y / dp << " dp)";
    EXPECT_GT(glm::dot(built, inwardNormal(g, p, r, 1e-3 * dp)), 0.49) << "point " << i;
    steepFrames += along < 0.9;
  }
  for (int e = 0; e < 5; ++e) EXPECT_GT(perElement[e], 100) << "element " << e;
  // Mirror symmetry across y = 0: every particle's image is a particle of its kind (exactly),
  // and a wall point's frame normal is the image of its image's.
  auto frameNormal = [&](std::uint32_t i) {
    const glm::dvec3 p(x[i]);
    const auto& w = b.network.points[i];
    return glm::normalize(glm::cross(sep(p, glm::dvec3(x[w.frameA])), sep(p, glm::dvec3(x[w.frameB]))));
  };
  for (std::uint32_t i = 0; i < b.particles.size(); ++i) {
    const glm::dvec3 image(x[i].x, -x[i].y, x[i].z);
    const bool wall = i < b.wall;
    double nearest = 1e9;
    std::uint32_t at = i;
    for (std::uint32_t j = wall ? 0 : b.wall; j < (wall ? b.wall : b.particles.size()); ++j) {
      const double dist = glm::length(sep(image, glm::dvec3(x[j])));
      if (dist < nearest) nearest = dist, at = j;
    }
    ASSERT_LT(nearest, 1e-6 * dp) << (wall ? "wall" : "fluid") << " particle " << i << " has no mirror image";
    if (wall) {
      const glm::dvec3 n = frameNormal(i), m = frameNormal(at);
      EXPECT_LT(glm::length(glm::dvec3(n.x, -n.y, n.z) - m), 1e-5) << "frames of point " << i << " and its image " << at;
    }
  }
  // The spheres at the bends cover the wedges on their outer sides (at the split and the
  // merge the legs cover the parent's end, and the spheres add nothing).
  EXPECT_GT(perElement[6], 20) << "no cover for the +bend's wedge";
  EXPECT_GT(perElement[8], 20) << "no cover for the -bend's wedge";
  // No hole: probes on the union's surface halfway between the layers (radius R + dp),
  // sampled densely on every element's surface, each have a wall point within 0.9 dp.
  const double rm = R + dp;
  int probes = 0;
  auto probe = [&](glm::dvec3 p) {
    if (std::abs(bifurcationDistance(g, p, rm)) > 1e-9) return;  // inside another element
    double nearest = 1e9;
    for (std::uint32_t w = 0; w < b.wall; ++w) nearest = std::min(nearest, glm::length(sep(p, glm::dvec3(x[w]))));
    EXPECT_LT(nearest, 0.9 * dp) << "hole at " << p.x << " " << p.y << " " << p.z;
    ++probes;
  };
  for (const auto& s : g.segments) {
    const double len = glm::length(s.b - s.a);
    const glm::dvec3 d = (s.b - s.a) / len, e1(0.0, 0.0, 1.0), e2 = glm::normalize(glm::cross(d, e1));
    for (int i = 0; i <= int(len / (0.3 * dp)); ++i)
      for (int k = 0; k < 64; ++k) {
        const double phi = 2.0 * std::numbers::pi * k / 64;
        probe(s.a + (i * 0.3 * dp) * d + rm * (std::cos(phi) * e1 + std::sin(phi) * e2));
      }
  }
  for (const glm::dvec3& c : g.joints)
    for (int k = 0; k < 800; ++k) {
      const double z = 1.0 - (2.0 * k + 1.0) / 800, rho = std::sqrt(1.0 - z * z), phi = 2.39996 * k;
      probe(c + rm * glm::dvec3(rho * std::cos(phi), rho * std::sin(phi), z));
    }
  EXPECT_GT(probes, 5000);
  // The fluid fills the lumen, inside it, about one particle per dp^3 (the lumen's volume by
  // counting points of a dp/3 grid).
  for (std::uint32_t i = b.wall; i < b.particles.size(); ++i) {
    EXPECT_LT(bifurcationDistance(g, glm::dvec3(x[i]), R), 0.0) << "fluid particle " << i << " outside the lumen";
    EXPECT_FALSE(outsideVessel(a, glm::vec3(x[i]), 0.0f));
  }
  const double step = dp / 3.0, top = g.joints[1].y + R;
  long cells = 0;
  for (double px = a.tube.x0 + 0.5 * step; px < a.tube.x0 + L; px += step)
    for (double py = -top; py < top; py += step)
      for (double pz = -R; pz < R; pz += step) cells += bifurcationDistance(g, glm::dvec3(px, py + 0.5 * step, pz + 0.5 * step), R) < 0.0;
  const double volume = cells * step * step * step;
  EXPECT_NEAR(b.particles.fluid * dp * dp * dp / volume, 1.0, 0.1);
  std::printf("bifurcation: %u wall points, %zu springs, %u fluid (lumen %.1f dp^3), %d probes, %d frames 25-60 deg off the normal\n",
              b.wall, b.network.springs.size(), b.particles.fluid, volume / (dp * dp * dp), probes, steepFrames);
  // Points outside the outer wall by more than the margin have escaped.
  EXPECT_TRUE(outsideVessel(a, glm::vec3(g.joints[1] + glm::dvec3(0.0, R + 4 * dp, 0.0)), float(dp)));
  EXPECT_FALSE(outsideVessel(a, glm::vec3(g.joints[1]), float(dp)));
}

TEST(Bifurcation, BadSpecsAreRejected) {
  auto rejects = [](AneurysmSpec a, const char* what) {
    try {
      buildBifurcation(a);
      ADD_FAILURE() << "accepted: " << what;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  AneurysmSpec a = spec();
  a.tube.periodic = false;
  rejects(a, "periodic");
  a = spec();
  a.branchAngle = 0.0f;
  rejects(a, "angle");
  a.branchAngle = float(85.0 * std::numbers::pi / 180.0);
  rejects(a, "angle");
  a = spec();
  a.branchLength = 10 * a.tube.spacing;
  rejects(a, "part at the bends");
  a = spec();
  a.branchLength = 20 * a.tube.spacing;
  rejects(a, "longer than the loop");
}

TEST(Bifurcation, SceneFilesAreCheckedAndBuild) {
  nlohmann::json j = nlohmann::json::parse(R"({
    "scene": "b",
    "particles": { "spacing_m": 3.5e-4 },
    "fluid": { "expected_max_speed_m_s": 0.5, "background_pressure_Pa": 800.0 },
    "vessel": { "shape": "bifurcation", "length_m": 0.01435, "radius_m": 0.0014, "branch_angle_deg": 30.0,
                "branch_length_m": 0.005, "point_mass_kg": 5e-6, "stiffness_N_m": 5.0,
                "inflow": { "profile": "parabolic", "mean_speed_m_s": 0.3, "zone_length_m": 0.0014 } },
    "forces": { "gravity_m_s2": [0, 0, 0] },
    "domain": { "min_m": [0.0, -0.005, -0.003], "max_m": [0.01435, 0.005, 0.003], "periodic": ["x"] }
  })");
  const Scene s = parseScene(j.dump(), "b.json");
  ASSERT_TRUE(s.vessel);
  EXPECT_EQ(s.vessel->shape, Vessel::Shape::Bifurcation);
  EXPECT_NEAR(s.vessel->branchAngle, std::numbers::pi / 6.0, 1e-6);
  const SceneBuild b = buildScene(s);
  EXPECT_EQ(b.particles.size(), countSceneParticles(s));
  EXPECT_GT(b.wall, 3000u);
  EXPECT_EQ(countEscaped(s, b.particles.positions, b.particles.velocities), 0u);

  nlohmann::json missing = j;
  missing["vessel"].erase("branch_length_m");
  expectError(missing, {"vessel.branch_length_m", "required"});
  nlohmann::json foreign = j;
  foreign["vessel"]["sac_radius_m"] = 0.002;
  expectError(foreign, {"vessel.sac_radius_m", "only applies to an aneurysm"});
  nlohmann::json tube = j;
  tube["vessel"]["shape"] = "tube";
  expectError(tube, {"vessel.branch_angle_deg", "only applies to a bifurcation"});
  nlohmann::json steep = j;
  steep["vessel"]["branch_angle_deg"] = 85.0;
  expectError(steep, {"vessel.branch_angle_deg"});
  nlohmann::json closed = j;
  closed["domain"].erase("periodic");
  closed["vessel"].erase("inflow");
  expectError(closed, {"domain.periodic", "bifurcation needs a periodic x axis"});
  nlohmann::json longZone = j;
  longZone["vessel"]["inflow"]["zone_length_m"] = 0.003;
  expectError(longZone, {"vessel.inflow.zone_length_m", "before the split"});
  nlohmann::json narrow = j;
  narrow["domain"]["max_m"][1] = 0.004;
  expectError(narrow, {"vessel", "outside the domain"});
  nlohmann::json shortLoop = j;
  shortLoop["vessel"]["branch_length_m"] = 0.004;
  expectError(shortLoop, {"vessel", "part at the bends"});

  // With open ends the loop is cut at the seam: no spring crosses the cut, and the wall
  // points within a spacing of either end are anchored (and only those).
  nlohmann::json open = j;
  open["domain"].erase("periodic");
  open["vessel"]["outlet"] = {{"condition", "pressure"}};
  const Scene os = parseScene(open.dump(), "b_open.json");
  const SceneBuild ob = buildScene(os);
  ASSERT_TRUE(ob.network);
  const double dp = os.sph.spacing, L = os.vessel->length;
  std::size_t anchoredStart = 0, anchoredEnd = 0, wrong = 0;
  for (std::uint32_t i = 0; i < ob.wall; ++i) {
    const double x = ob.particles.positions[i].x;
    const bool nearEnd = x < dp || x > L - dp;
    wrong += ob.network->points[i].anchored != nearEnd;
    anchoredStart += ob.network->points[i].anchored && x < dp;
    anchoredEnd += ob.network->points[i].anchored && x > L - dp;
  }
  EXPECT_EQ(wrong, 0u);
  EXPECT_GT(anchoredStart, 20u);
  EXPECT_GT(anchoredEnd, 20u);
  double longest = 0.0;
  for (const auto& sp : ob.network->springs) {
    longest = std::max(longest, double(glm::length(ob.particles.positions[sp.a] - ob.particles.positions[sp.b])));
  }
  EXPECT_LT(longest, 2.0 * dp) << "a spring links across the cut";
  EXPECT_EQ(countEscaped(os, ob.particles.positions, ob.particles.velocities), 0u);
  nlohmann::json longBuffer = open;
  longBuffer["vessel"]["outlet"]["buffer_length_m"] = 0.002;
  expectError(longBuffer, {"vessel.outlet.buffer_length_m", "after the merge"});
}

}  // namespace
}  // namespace hemo::scene
