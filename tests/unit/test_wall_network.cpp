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
