// The fusiform aneurysm builder (a bulge all round the tube) and its scene section.
#include "hemo/scene/build.hpp"
#include "hemo/scene/fusiform.hpp"
#include "hemo/scene/scene.hpp"
#include "artery_spec.hpp"
#include "scene_errors.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <numbers>

namespace hemo::scene {
namespace {

using Json = nlohmann::json;

// R = 5 dp, bulging to 8 dp over 14 dp, in a periodic tube 28 dp long.
AneurysmSpec spec() {
  AneurysmSpec a;
  a.tube = arteryTube(28);
  const TubeSpec& t = a.tube;
  a.bulgeRadius = 8 * t.spacing;
  a.bulgeLength = 14 * t.spacing;
  return a;
}

TEST(Fusiform, WallFollowsTheProfileWithoutHoles) {
  const AneurysmSpec a = spec();
  const FusiformBuild b = buildFusiformAneurysm(a);
  const double dp = a.tube.spacing;
  const auto& x = b.particles.positions;
  // Every wall point on its layer's surface of revolution; every frame's normal inward.
  std::vector<int> springsOf(b.wall, 0);
  for (const auto& s : b.network.springs) ++springsOf[s.a], ++springsOf[s.b];
  std::uint32_t inBulge = 0;
  for (std::uint32_t i = 0; i < b.wall; ++i) {
    const double r = std::hypot(x[i].y, x[i].z), inner = innerRadiusAt(a, x[i].x);
    const double layer = (r - inner) / dp - 0.5;
    EXPECT_NEAR(layer, std::round(layer), 1e-3) << "point " << i << " is off its layer";
    EXPECT_GE(springsOf[i], 4) << "point " << i;
    inBulge += b.inBulge[i];
    const auto& w = b.network.points[i];
    ASSERT_NE(w.frameA, sim::WallPoint::kNoFrame) << "point " << i << " has no frame";
    glm::dvec3 ea = glm::dvec3(x[w.frameA]) - glm::dvec3(x[i]), eb = glm::dvec3(x[w.frameB]) - glm::dvec3(x[i]);
    for (glm::dvec3* e : {&ea, &eb}) e->x -= a.tube.length * std::round(e->x / a.tube.length);
    const glm::dvec3 n = glm::normalize(glm::cross(ea, eb));
    EXPECT_GT(glm::dot(n, -glm::normalize(glm::dvec3(0.0, x[i].y, x[i].z))), 0.5) << "point " << i;
  }
  EXPECT_GT(inBulge, b.wall / 4);
  // No hole: probes halfway between the layers, all over the vessel, have a wall point within 0.9 dp.
  int probes = 0;
  for (int i = 0; i < 200; ++i)
    for (int k = 0; k < 60; ++k) {
      const double px = a.tube.x0 + a.tube.length * (i + 0.5) / 200, theta = 2.0 * std::numbers::pi * k / 60;
      const double r = innerRadiusAt(a, px) + dp;
      const glm::dvec3 p(px, r * std::cos(theta), r * std::sin(theta));
      double nearest = 1e9;
      for (std::uint32_t w = 0; w < b.wall; ++w) {
        glm::dvec3 d = glm::dvec3(x[w]) - p;
        d.x -= a.tube.length * std::round(d.x / a.tube.length);
        nearest = std::min(nearest, glm::length(d));
      }
      EXPECT_LT(nearest, 0.9 * dp) << "hole at x " << px << " theta " << theta;
      ++probes;
    }
  // The fluid fills the lumen, clear of the wall, about one particle per dp^3.
  double volume = 0.0;
  for (int i = 0; i < 1000; ++i) {
    const double r = innerRadiusAt(a, a.tube.x0 + a.tube.length * (i + 0.5) / 1000);
    volume += std::numbers::pi * r * r * a.tube.length / 1000;
  }
  for (std::uint32_t i = b.wall; i < b.particles.size(); ++i) {
    EXPECT_LT(std::hypot(x[i].y, x[i].z), innerRadiusAt(a, x[i].x)) << "fluid particle " << i << " outside the lumen";
  }
  EXPECT_NEAR(b.particles.fluid * dp * dp * dp / volume, 1.0, 0.1);
  std::printf("fusiform: %u wall points, %zu springs, %u fluid (lumen %.1f dp^3), %d probes\n", b.wall,
              b.network.springs.size(), b.particles.fluid, volume / (dp * dp * dp), probes);
}

TEST(Fusiform, BadSpecsAndScenesAreRejected) {
  AneurysmSpec a = spec();
  a.bulgeRadius = a.tube.radius;
  EXPECT_THROW(buildFusiformAneurysm(a), std::invalid_argument);
  a = spec();
  a.bulgeLength = 27 * a.tube.spacing;
  EXPECT_THROW(buildFusiformAneurysm(a), std::invalid_argument);
  Json j = Json::parse(R"({
    "scene": "f",
    "particles": { "spacing_m": 3.5e-4 },
    "fluid": { "expected_max_speed_m_s": 0.5 },
    "vessel": { "shape": "fusiform_aneurysm", "length_m": 0.0098, "radius_m": 0.00175, "point_mass_kg": 5e-6,
                "stiffness_N_m": 5.0, "bulge_radius_m": 0.0028, "bulge_length_m": 0.0049 },
    "forces": { "gravity_m_s2": [0, 0, 0] },
    "domain": { "min_m": [0.0, -0.004, -0.004], "max_m": [0.0098, 0.004, 0.004], "periodic": ["x"] }
  })");
  const Scene s = parseScene(j.dump(), "f.json");
  const SceneBuild b = buildScene(s);
  EXPECT_EQ(b.particles.size(), countSceneParticles(s));
  Json noBulge = j;
  noBulge["vessel"].erase("bulge_length_m");
  expectError(noBulge, {"vessel.bulge_length_m", "required"});
  Json sacKey = j;
  sacKey["vessel"]["sac_radius_m"] = 0.002;
  expectError(sacKey, {"vessel.sac_radius_m", "does not apply"});
  Json narrow = j;
  narrow["vessel"]["bulge_radius_m"] = 0.0015;
  expectError(narrow, {"vessel.bulge_radius_m", "exceed"});
  Json small = j;
  small["domain"]["max_m"][2] = 0.003;
  expectError(small, {"vessel", "outside the domain"});
}

}  // namespace
}  // namespace hemo::scene
