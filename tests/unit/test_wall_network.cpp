// Spring-network validation: every bad input is named.
#include "hemo/sim/wall.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace hemo::sim {
namespace {

SpringNetwork triangle() {
  SpringNetwork n;
  n.points = {{0.01f, true}, {0.01f, false}, {0.01f, false}};
  n.springs = {{0, 1, 0.1f, 10.0f, 0.1f, 5.0f}, {1, 2, 0.1f, 10.0f, 0.1f, 5.0f}, {2, 0, 0.1f, 10.0f, 0.1f, 5.0f}};
  return n;
}

void expectRejected(const SpringNetwork& n, const std::string& fragment) {
  try {
    n.validate();
    FAIL() << "accepted; expected an error containing '" << fragment << "'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(SpringNetwork, ValidNetworkPasses) { EXPECT_NO_THROW(triangle().validate()); }

TEST(SpringNetwork, BadSpringsAndPointsAreNamed) {
  SpringNetwork n = triangle();
  n.springs[1].b = 7;
  expectRejected(n, "spring 1 (1-7): particle id beyond the 3 wall points");
  n = triangle();
  n.springs[2].b = 2;
  expectRejected(n, "spring 2 (2-2): connects a particle to itself");
  n = triangle();
  n.springs.push_back({1, 0, 0.1f, 1.0f, 0.0f, 1.0f});
  expectRejected(n, "spring 3 (1-0): duplicate spring");
  n = triangle();
  n.springs[0].restLength = 0.0f;
  expectRejected(n, "spring 0 (0-1): rest length must be positive");
  n = triangle();
  n.springs[0].stiffness = -1.0f;
  expectRejected(n, "spring 0 (0-1): stiffness");
  n = triangle();
  n.springs[0].damping = NAN;
  expectRejected(n, "spring 0 (0-1): damping");
  n = triangle();
  n.springs[0].maxForce = -2.0f;
  expectRejected(n, "spring 0 (0-1): maximum force");
  n = triangle();
  n.points[2].mass = 0.0f;
  expectRejected(n, "wall point 2: mass must be positive");
  n = triangle();
  n.timeStepFactor = 0.0f;
  expectRejected(n, "time-step factor");
  n = triangle();
  n.points[1].frameA = 0;  // frameB missing
  expectRejected(n, "wall point 1: its normal's frame needs two other points");
  n.points[1].frameB = 1;  // itself
  expectRejected(n, "wall point 1: its normal's frame");
  n.points[1].frameB = 9;  // out of range
  expectRejected(n, "wall point 1: its normal's frame");
  n.points[1].frameB = 2;
  EXPECT_NO_THROW(n.validate());
}

}  // namespace
}  // namespace hemo::sim

// The tube builder: lattice counts, springs at their built lengths, frames that give the
// inward normal, anchors at the ends, fluid strictly inside, bad specs named.
#include "hemo/scene/tube.hpp"

#include <glm/geometric.hpp>

namespace hemo::scene {
namespace {

TubeSpec smallTube() {
  TubeSpec t;
  t.length = 0.012f;
  t.radius = 0.005f;
  t.spacing = 0.001f;
  t.layers = 2;
  t.pointMass = 1e-4f;
  t.stiffness = 10.0f;
  t.fluidMass = 1e-6f;
  return t;
}

TEST(Tube, LatticeSpringsFramesAndFluid) {
  for (bool periodic : {false, true}) {
    TubeSpec t = smallTube();
    t.periodic = periodic;
    const TubeBuild b = buildTube(t);
    EXPECT_EQ(b.along, 12u);
    EXPECT_EQ(b.around, 31u);  // round(2 pi 5)
    EXPECT_EQ(b.wall, 2u * 12u * 31u);
    EXPECT_EQ(b.network.points.size(), b.wall);
    const auto& x = b.particles.positions;
    std::size_t anchored = 0;
    for (std::uint32_t i = 0; i < b.wall; ++i) {
      const auto& p = b.network.points[i];
      anchored += p.anchored;
      glm::vec3 a = glm::vec3(x[p.frameA]) - glm::vec3(x[i]), c = glm::vec3(x[p.frameB]) - glm::vec3(x[i]);
      if (periodic) a.x -= t.length * std::round(a.x / t.length), c.x -= t.length * std::round(c.x / t.length);
      const glm::vec3 n = glm::normalize(glm::cross(a, c));
      const glm::vec3 inward = glm::normalize(glm::vec3(0.0f, -x[i].y, -x[i].z));
      EXPECT_GT(glm::dot(n, inward), 0.99f) << "frame of wall point " << i;
      EXPECT_GT(glm::dot(glm::vec3(b.particles.normals[i]), inward), 0.999f);
    }
    EXPECT_EQ(anchored, periodic ? 0u : 2u * 2u * 31u) << "the end rings of both layers";
    for (const auto& s : b.network.springs) {
      glm::vec3 d = glm::vec3(x[s.b]) - glm::vec3(x[s.a]);
      if (periodic) d.x -= t.length * std::round(d.x / t.length);
      EXPECT_NEAR(s.restLength, glm::length(d), 1e-6f);
      EXPECT_LT(s.restLength, 2.0f * t.spacing);
    }
    // The fluid's rings reach half a spacing from the lumen's edge (a spacing from the wall's
    // first layer) all round, with one particle per dp^2 of the cross-section.
    float outer = 0.0f;
    for (std::uint32_t i = b.wall; i < b.particles.size(); ++i) {
      const float r = std::hypot(x[i].y, x[i].z);
      EXPECT_LE(r, t.radius - 0.5f * t.spacing + 1e-6f);
      outer = std::max(outer, r);
      for (std::uint32_t j = b.wall; j < i; ++j) EXPECT_GT(glm::length(x[j] - x[i]), 0.45f * t.spacing) << i << " crowds " << j;
    }
    EXPECT_NEAR(outer, t.radius - 0.5f * t.spacing, 1e-6f);
    EXPECT_EQ(b.particles.fluid, 12u * (3u + 9u + 16u + 22u + 28u));  // rings at 0.5 .. 4.5 dp: round(2 pi r / dp)
    EXPECT_NEAR(double(b.particles.fluid) / 12.0, std::numbers::pi * 25.0, 1.0);  // pi R^2 / dp^2
  }
}

TEST(Tube, BadSpecsAreRejected) {
  TubeSpec t = smallTube();
  t.radius = 0.0f;
  EXPECT_THROW(buildTube(t), std::invalid_argument);
  t = smallTube();
  t.periodic = true;
  t.length = 0.0125f;  // 12.5 spacings
  EXPECT_THROW(buildTube(t), std::invalid_argument);
  t = smallTube();
  t.layers = 0;
  EXPECT_THROW(buildTube(t), std::invalid_argument);
}

}  // namespace
}  // namespace hemo::scene
