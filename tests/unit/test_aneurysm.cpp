// The saccular aneurysm builder and the vessel section of scene files.
#include "hemo/scene/aneurysm.hpp"
#include "hemo/scene/build.hpp"
#include "hemo/scene/scene.hpp"
#include "hemo/scene/tube.hpp"
#include "artery_spec.hpp"
#include "scene_errors.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <numbers>

namespace hemo::scene {
namespace {

using Json = nlohmann::json;

// The shipped scene's proportions: R = 5 dp, Rs = 8 dp, neck 6.9 dp, 32 dp long, periodic.
AneurysmSpec spec() {
  AneurysmSpec a;
  a.tube = arteryTube(32);
  const TubeSpec& t = a.tube;
  a.sacRadius = 8 * t.spacing;
  a.neckWidth = 2.4e-3f;
  a.sacStrengthScale = 0.5f;
  return a;
}

double dist(glm::vec4 a, glm::vec4 b) { return glm::length(glm::dvec3(a) - glm::dvec3(b)); }

TEST(Aneurysm, WallSurfacesSpringsAndFrames) {
  const AneurysmSpec a = spec();
  const AneurysmBuild b = buildSaccularAneurysm(a);
  const double dp = a.tube.spacing;
  const glm::dvec3 c(b.sacCentre);
  const auto& x = b.particles.positions;
  ASSERT_EQ(b.network.points.size(), b.wall);
  ASSERT_EQ(b.inSac.size(), b.wall);
  // Centre: sqrt(R^2 - w^2/4) + sqrt(Rs^2 - w^2/4) above the axis, halfway along.
  EXPECT_NEAR(c.z, std::sqrt(1.75e-3 * 1.75e-3 - 1.44e-6) + std::sqrt(2.8e-3 * 2.8e-3 - 1.44e-6), 1e-7);
  EXPECT_NEAR(c.x, 16 * dp, 1e-7);
  std::size_t sac = 0;
  for (std::uint32_t i = 0; i < b.wall; ++i) {
    const glm::dvec3 p(x[i]);
    const double axis = std::hypot(p.y, p.z), centre = glm::length(p - c);
    // On a layer of its surface: radius + (l + 1/2) dp.
    const double layer = b.inSac[i] ? (centre - a.sacRadius) / dp - 0.5 : (axis - a.tube.radius) / dp - 0.5;
    EXPECT_NEAR(layer, std::round(layer), 1e-3) << "wall point " << i;
    EXPECT_TRUE(layer > -0.01 && layer < a.tube.layers - 0.99) << "wall point " << i;
    // Not inside the other surface's lumen.
    if (b.inSac[i]) EXPECT_GE(axis, a.tube.radius + 0.5 * dp - 1e-7) << i;
    else EXPECT_GE(centre, a.sacRadius + 0.5 * dp - 1e-7) << i;
    sac += b.inSac[i];
    // The frame's normal points into the fluid (towards the axis or the sac's centre).
    const sim::WallPoint& w = b.network.points[i];
    ASSERT_NE(w.frameA, sim::WallPoint::kNoFrame) << "wall point " << i << " has no frame";
    glm::dvec3 ea = glm::dvec3(x[w.frameA]) - p, eb = glm::dvec3(x[w.frameB]) - p;
    ea.x -= a.tube.length * std::round(ea.x / a.tube.length);
    eb.x -= a.tube.length * std::round(eb.x / a.tube.length);
    const glm::dvec3 n = glm::normalize(glm::cross(ea, eb));
    const glm::dvec3 inward = b.inSac[i] ? glm::normalize(c - p) : glm::normalize(glm::dvec3(0.0, -p.y, -p.z));
    EXPECT_GT(glm::dot(n, inward), 0.5) << "frame of wall point " << i;
  }
  EXPECT_GT(sac, 1000u);
  EXPECT_LT(sac, b.wall);
  // Springs: built lengths, short, and the sac's with the sac's parameters.
  std::vector<int> degree(b.wall, 0);
  for (const auto& s : b.network.springs) {
    glm::dvec3 d = glm::dvec3(x[s.b]) - glm::dvec3(x[s.a]);
    d.x -= a.tube.length * std::round(d.x / a.tube.length);
    EXPECT_NEAR(s.restLength, glm::length(d), 1e-9);
    EXPECT_LT(s.restLength, 2.0 * dp);
    const bool sacSpring = b.inSac[s.a] || b.inSac[s.b];
    EXPECT_FLOAT_EQ(s.maxForce, sacSpring ? 0.5f * a.tube.maxForce : a.tube.maxForce);
    ++degree[s.a], ++degree[s.b];
  }
  for (std::uint32_t i = 0; i < b.wall; ++i) EXPECT_GE(degree[i], 4) << "wall point " << i << " is loosely held";
}

// No hole in the wall: every point between the two layers of the tube (outside the sac) and
// of the sac (outside the tube) has a wall point within 0.9 dp, neck included.
TEST(Aneurysm, WallIsClosedAtTheNeck) {
  const AneurysmSpec a = spec();
  const AneurysmBuild b = buildSaccularAneurysm(a);
  const double dp = a.tube.spacing;
  const glm::dvec3 c(b.sacCentre);
  auto nearest = [&](glm::dvec3 p) {
    double best = 1.0;
    for (std::uint32_t i = 0; i < b.wall; ++i) best = std::min(best, glm::length(glm::dvec3(b.particles.positions[i]) - p));
    return best;
  };
  const double mid = dp;  // between the layers at +dp/2 and +3dp/2
  int probes = 0;
  for (int i = 0; i < 64; ++i)
    for (int k = 0; k < 48; ++k) {
      const double theta = 2.0 * std::numbers::pi * k / 48;
      const glm::dvec3 p((i + 0.5) * a.tube.length / 64, (a.tube.radius + mid) * std::cos(theta), (a.tube.radius + mid) * std::sin(theta));
      if (glm::length(p - c) < a.sacRadius + mid) continue;
      EXPECT_LT(nearest(p), 0.9 * dp) << "hole in the tube wall at " << p.x << " " << p.y << " " << p.z;
      ++probes;
    }
  for (int k = 0; k < 2000; ++k) {
    const double z = 1.0 - (2.0 * k + 1.0) / 2000, r = std::sqrt(1.0 - z * z), phi = 2.39996 * k;
    const glm::dvec3 p = c + (a.sacRadius + mid) * glm::dvec3(r * std::cos(phi), r * std::sin(phi), z);
    if (std::hypot(p.y, p.z) < a.tube.radius + mid) continue;
    EXPECT_LT(nearest(p), 0.9 * dp) << "hole in the sac wall at " << p.x << " " << p.y << " " << p.z;
    ++probes;
  }
  EXPECT_GT(probes, 3000);
}

TEST(Aneurysm, FluidFillsTubeAndSacClearOfTheWall) {
  const AneurysmSpec a = spec();
  const AneurysmBuild b = buildSaccularAneurysm(a);
  const double dp = a.tube.spacing;
  const glm::dvec3 c(b.sacCentre);
  std::size_t inSac = 0;
  for (std::uint32_t f = b.wall; f < b.particles.size(); ++f) {
    const glm::dvec3 p(b.particles.positions[f]);
    EXPECT_EQ(b.particles.velocities[f].w, 0.0f);
    const bool tube = std::hypot(p.y, p.z) < a.tube.radius, sac = glm::length(p - c) < a.sacRadius;
    EXPECT_TRUE(tube || sac) << "fluid outside the lumen at " << p.x << " " << p.y << " " << p.z;
    inSac += !tube;
    for (std::uint32_t w = 0; w < b.wall; ++w) ASSERT_GE(dist(b.particles.positions[f], b.particles.positions[w]), 0.8 * dp - 1e-9);
  }
  // The sac's lumen outside the tube: about (4/3 pi Rs^3 - overlap) / dp^3; at least half.
  EXPECT_GT(double(inSac), 0.5 * 4.0 / 3.0 * std::numbers::pi * std::pow(8.0, 3.0) * 0.7);
  EXPECT_EQ(b.particles.fluid + b.wall, b.particles.size());
}

// Laplace's law for a sphere (T = P r / 2): the sac's rupture pressure from its springs falls
// like 1 / Rs, and lies below the tube's (T = P R) with the shipped proportions.
TEST(Aneurysm, SacRupturePressureFollowsLaplace) {
  AneurysmSpec a = spec();
  const double small = sacRupturePressure(buildSaccularAneurysm(a));
  const double tube = hoopRupturePressure(a.tube, buildTube(a.tube));
  EXPECT_LT(small, 0.5 * tube);
  a.sacStrengthScale = 1.0f;
  const double strong = sacRupturePressure(buildSaccularAneurysm(a));
  EXPECT_NEAR(strong / small, 2.0, 1e-6);
  a.tube.length = 48 * a.tube.spacing;
  a.sacRadius = 12 * a.tube.spacing;
  a.neckWidth = 2.4e-3f;
  const double large = sacRupturePressure(buildSaccularAneurysm(a));
  EXPECT_NEAR(large / strong, 8.0 / 12.0, 0.1 * 8.0 / 12.0) << strong << " Pa at Rs = 8 dp, " << large << " Pa at 12 dp";
}

TEST(Aneurysm, BadSpecsAreRejected) {
  AneurysmSpec a = spec();
  a.sacRadius = 0.0f;
  EXPECT_THROW(buildSaccularAneurysm(a), std::invalid_argument);
  a = spec();
  a.neckWidth = 2.0f * a.tube.radius;
  EXPECT_THROW(buildSaccularAneurysm(a), std::invalid_argument);
  a = spec();
  a.tube.length = 16 * a.tube.spacing;  // shorter than the sac
  EXPECT_THROW(buildSaccularAneurysm(a), std::invalid_argument);
  a = spec();
  a.sacStrengthScale = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(buildSaccularAneurysm(a), std::invalid_argument);
}

TEST(Aneurysm, OutsideVesselSeparatesLumenFromTheOutside) {
  const AneurysmSpec a = spec();
  const AneurysmBuild b = buildSaccularAneurysm(a);
  const float dp = a.tube.spacing;
  for (std::uint32_t i = 0; i < b.particles.size(); ++i) EXPECT_FALSE(outsideVessel(a, glm::vec3(b.particles.positions[i]), dp)) << i;
  EXPECT_TRUE(outsideVessel(a, b.sacCentre + glm::vec3(0.0f, 0.0f, a.sacRadius + 4 * dp), dp));
  EXPECT_TRUE(outsideVessel(a, glm::vec3(0.001f, 0.0f, -a.tube.radius - 4 * dp), dp));
  EXPECT_FALSE(outsideVessel(a, glm::vec3(0.001f, 0.0f, 0.0f), dp));
}

Json vesselScene() {
  return Json::parse(R"({
    "scene": "v",
    "particles": { "spacing_m": 3.5e-4 },
    "fluid": { "expected_max_speed_m_s": 0.5, "background_pressure_Pa": 100.0, "background_pressure_ramp_s": 0.01 },
    "vessel": { "shape": "saccular_aneurysm", "length_m": 0.0112, "radius_m": 0.00175, "point_mass_kg": 5e-6,
                "stiffness_N_m": 5.0, "max_force_N": 1e-3, "sac_radius_m": 0.0028, "neck_width_m": 0.0024 },
    "forces": { "gravity_m_s2": [0, 0, 0] },
    "domain": { "min_m": [0.0, -0.005, -0.0035], "max_m": [0.0112, 0.005, 0.012], "periodic": ["x"] }
  })");
}


TEST(VesselScene, LoadsBuildsAndCounts) {
  const Scene s = parseScene(vesselScene().dump(), "v.json");
  ASSERT_TRUE(s.vessel);
  EXPECT_TRUE(s.vessel->periodic);
  EXPECT_FLOAT_EQ(s.sph.backgroundPressure, 100.0f);
  EXPECT_FLOAT_EQ(s.sph.backgroundPressureRamp, 0.01f);
  EXPECT_TRUE(s.blocks.empty());
  const SceneBuild b = buildScene(s);
  ASSERT_TRUE(b.network);
  EXPECT_EQ(b.network->points.size(), b.wall);
  EXPECT_EQ(b.particles.size(), countSceneParticles(s));
  EXPECT_EQ(b.particles.size(), b.wall + b.particles.fluid);
  for (std::uint32_t i = 0; i < b.particles.size(); ++i) {
    EXPECT_EQ(b.particles.ids[i], i);
    EXPECT_EQ(b.particles.velocities[i].w, i < b.wall ? 2.0f : 0.0f);
  }
  Json tube = vesselScene();
  tube["vessel"]["shape"] = "tube";
  for (const char* key : {"sac_radius_m", "neck_width_m"}) tube["vessel"].erase(key);
  const Scene t = parseScene(tube.dump(), "t.json");
  EXPECT_EQ(buildScene(t).particles.size(), countSceneParticles(t));
}

TEST(VesselScene, BadVesselsAreNamed) {
  Json j = vesselScene();
  j["vessel"].erase("sac_radius_m");
  expectError(j, {"vessel.sac_radius_m", "required"});
  j = vesselScene();
  j["vessel"]["shape"] = "tube";
  expectError(j, {"vessel.sac_radius_m", "saccular_aneurysm"});
  j = vesselScene();
  j["vessel"].erase("stiffness_N_m");
  expectError(j, {"vessel.stiffness_N_m", "neither"});
  j = vesselScene();
  j["vessel"]["length_m"] = 0.01;
  expectError(j, {"vessel.length_m", "span the domain"});
  j = vesselScene();
  j["domain"]["max_m"][2] = 0.006;
  expectError(j, {"vessel", "outside the domain"});
  j = vesselScene();
  j["vessel"]["neck_width_m"] = 0.004;
  expectError(j, {"vessel.neck_width_m"});
  j = vesselScene();
  j["vessel"]["shape"] = "none";
  expectError(j, {"vessel.", "vessel.shape"});
  j = vesselScene();
  j["vessel"]["shape"] = "bulge";
  expectError(j, {"vessel.shape", "unknown value"});
  j = vesselScene();
  j["fluid"]["background_pressure_Pa"] = -1.0;
  expectError(j, {"fluid.background_pressure_Pa"});
}

TEST(VesselScene, InflowIsParsedIntoTheTubesFrame) {
  Json j = vesselScene();
  j["vessel"]["start_m"] = {0.0, 0.001, -0.0005};
  j["domain"]["min_m"] = {0.0, -0.004, -0.004};
  j["vessel"]["inflow"] = Json::parse(R"({ "profile": "plug", "mean_speed_m_s": 0.2, "zone_length_m": 0.0014,
                                           "pulse_period_s": 0.5, "waveform": [1.0, 2.0, 0.5], "ramp_s": 0.01,
                                           "hold_lumen_pressure": true, "max_mass_ratio": 3.0 })");
  const Scene s = parseScene(j.dump(), "v.json");
  ASSERT_TRUE(s.vessel && s.vessel->inflow);
  const sim::Inflow& f = *s.vessel->inflow;
  EXPECT_EQ(f.profile, sim::Inflow::Profile::Plug);
  EXPECT_FLOAT_EQ(f.zoneStart, 0.0f);
  EXPECT_FLOAT_EQ(f.zoneEnd, 0.0014f);
  EXPECT_FLOAT_EQ(f.centreY, 0.001f);
  EXPECT_FLOAT_EQ(f.centreZ, -0.0005f);
  EXPECT_FLOAT_EQ(f.radius, 0.00175f);
  EXPECT_EQ(f.waveform.size(), 3u);
  EXPECT_TRUE(f.holdPressure);
  EXPECT_FLOAT_EQ(f.maxMassRatio, 3.0f);
  EXPECT_FALSE(parseScene(vesselScene().dump(), "v.json").vessel->inflow) << "no inflow unless a profile is chosen";
}

TEST(VesselScene, BadInflowsAreNamed) {
  auto with = [](const char* inflow) {
    Json j = vesselScene();
    j["vessel"]["inflow"] = Json::parse(inflow);
    return j;
  };
  expectError(with(R"({ "profile": "parabolic", "mean_speed_m_s": 0.2, "zone_length_m": 0.0003 })"),
              {"vessel.inflow.zone_length_m", "kernel support"});
  Json continuity = with(R"({ "profile": "parabolic", "mean_speed_m_s": 0.2, "zone_length_m": 0.0014 })");
  continuity["fluid"]["density"] = "continuity";
  expectError(continuity, {"vessel.inflow", "fluid.density \"continuity\""});
  expectError(with(R"({ "profile": "parabolic", "mean_speed_m_s": 0.2, "zone_length_m": 0.007 })"),
              {"vessel.inflow.zone_length_m", "half the tube"});
  expectError(with(R"({ "profile": "parabolic", "zone_length_m": 0.0014 })"), {"vessel.inflow.mean_speed_m_s", "non-zero"});
  expectError(with(R"({ "profile": "plug", "mean_speed_m_s": 0.2, "zone_length_m": 0.0014, "waveform": [1.0, 2.0] })"),
              {"vessel.inflow.pulse_period_s", "positive"});
  expectError(with(R"({ "profile": "plug", "mean_speed_m_s": 0.2, "zone_length_m": 0.0014, "pulse_period_s": 1.0 })"),
              {"vessel.inflow.waveform", "required"});
  expectError(with(R"({ "profile": "plug", "mean_speed_m_s": 0.2, "zone_length_m": 0.0014, "pulse_period_s": 1.0, "waveform": [1.0] })"),
              {"vessel.inflow.waveform", "2 to 64"});
  expectError(with(R"({ "profile": "plug", "mean_speed_m_s": 0.2, "zone_length_m": 0.0014, "pulse_period_s": 1.0, "waveform": [1.0, "x"] })"),
              {"vessel.inflow.waveform[1]", "number"});
  expectError(with(R"({ "profile": "sideways" })"), {"vessel.inflow.profile", "unknown value"});
  expectError(with(R"({ "mean_speed_m_s": 0.2 })"), {"vessel.inflow.mean_speed_m_s", "profile"});
  Json noPressure = with(R"({ "profile": "plug", "mean_speed_m_s": 0.2, "zone_length_m": 0.0014 })");
  noPressure["fluid"].erase("background_pressure_Pa");
  expectError(noPressure, {"fluid.background_pressure_Pa", "inflow"});
  Json closed = with(R"({ "profile": "plug", "mean_speed_m_s": 0.2, "zone_length_m": 0.0014 })");
  closed["domain"]["periodic"] = Json::array();
  closed["domain"]["min_m"][0] = -0.001;
  closed["domain"]["max_m"][0] = 0.0123;
  expectError(closed, {"vessel.inflow", "periodic"});
}

// Tissue properties mapped onto the springs: the built lattice then widens under lumen
// pressure P as a thin elastic tube does, u = (1 - nu^2) P R^2 / (E t), and ruptures at
// Laplace's P* = sigma_f t / R.
TEST(VesselScene, TissuePropertiesSetTheSprings) {
  Json j = vesselScene();
  j["vessel"]["shape"] = "tube";
  for (const char* key : {"sac_radius_m", "neck_width_m", "stiffness_N_m", "max_force_N"}) j["vessel"].erase(key);
  const double E = 1.5e6, nu = 0.45, t = 2.5e-4, sigma = 1.2e6;  // artery-like (docs/physics.md)
  j["vessel"]["youngs_modulus_Pa"] = E;
  j["vessel"]["poisson_ratio"] = nu;
  j["vessel"]["wall_thickness_m"] = t;
  j["vessel"]["failure_stress_Pa"] = sigma;
  const Scene s = parseScene(j.dump(), "v.json");
  const TubeSpec spec = vesselSpec(s).tube;
  const TubeBuild b = buildTube(spec);
  EXPECT_NEAR(hoopStiffness(spec, b) / (E * t / ((1.0 - nu * nu) * spec.radius * spec.radius)), 1.0, 1e-5);
  EXPECT_NEAR(hoopRupturePressure(spec, b) / (sigma * t / spec.radius), 1.0, 1e-5);
  std::printf("E %.3g Pa, t %.3g m -> k = %.4g N/m; sigma_f %.3g Pa -> f_max = %.4g N (P* = %.0f Pa)\n", E, t,
              spec.stiffness, sigma, spec.maxForce, hoopRupturePressure(spec, b));
  Json both = j;
  both["vessel"]["stiffness_N_m"] = 5.0;
  expectError(both, {"vessel.stiffness_N_m", "both"});
  Json noThickness = j;
  noThickness["vessel"].erase("wall_thickness_m");
  expectError(noThickness, {"vessel.wall_thickness_m", "required"});
  Json stray = vesselScene();
  stray["vessel"]["wall_thickness_m"] = 1e-4;
  expectError(stray, {"vessel.wall_thickness_m", "only applies"});
  Json bothForce = j;
  bothForce["vessel"]["max_force_N"] = 1e-3;
  expectError(bothForce, {"vessel.failure_stress_Pa", "not both"});
  Json incompressible = j;
  incompressible["vessel"]["poisson_ratio"] = 0.5;
  expectError(incompressible, {"vessel.poisson_ratio", "below 0.5"});
}

// The CPU evaluation of the waveform (the reference of sph/integrate.comp's).
TEST(Inflow, WaveformRampAndProfile) {
  sim::Inflow f;
  f.zoneStart = 0.0f;
  f.zoneEnd = 0.001f;
  f.radius = 0.002f;
  f.meanSpeed = 0.4f;
  f.period = 1.0f;
  f.waveform = {1.0f, 3.0f, 2.0f, 0.0f};
  EXPECT_NEAR(f.meanSpeedAt(0.0), 0.4, 1e-7);
  EXPECT_NEAR(f.meanSpeedAt(0.125), 0.4 * 2.0, 1e-6);   // halfway between samples 0 and 1
  EXPECT_NEAR(f.meanSpeedAt(0.875), 0.4 * 0.5, 1e-6);   // between the last sample and the first
  EXPECT_NEAR(f.meanSpeedAt(2.25), 0.4 * 3.0, 1e-6);    // periodic
  EXPECT_NEAR(f.meanSpeedAt(-0.75), 0.4 * 3.0, 1e-6);
  f.ramp = 0.5f;
  EXPECT_NEAR(f.meanSpeedAt(0.25), 0.4 * 3.0 * 0.5, 1e-6);
  EXPECT_NEAR(f.axialVelocity(2.0, 0.0), 2.0 * 0.4, 1e-6);  // parabolic: the peak is twice the mean
  EXPECT_NEAR(f.axialVelocity(2.0, 0.001), 2.0 * 0.4 * 0.75, 1e-6);
  EXPECT_EQ(f.axialVelocity(2.0, 0.003), 0.0);
  f.profile = sim::Inflow::Profile::Plug;
  EXPECT_NEAR(f.axialVelocity(2.0, 0.0019), 0.4, 1e-6);
  // The mean of the parabolic profile over the disc is the mean speed.
  f.profile = sim::Inflow::Profile::Parabolic;
  double flux = 0.0;
  const int rings = 2000;
  for (int k = 0; k < rings; ++k) {
    const double r = (k + 0.5) * f.radius / rings;
    flux += f.axialVelocity(2.0, r) * 2.0 * std::numbers::pi * r * (f.radius / rings);
  }
  EXPECT_NEAR(flux / (std::numbers::pi * f.radius * f.radius), 0.4, 1e-6);
  f.waveform = {1.0f};
  EXPECT_THROW(f.validate(), std::invalid_argument);
  f.waveform = {1.0f, 2.0f};
  f.period = 0.0f;
  EXPECT_THROW(f.validate(), std::invalid_argument);
}

}  // namespace
}  // namespace hemo::scene
