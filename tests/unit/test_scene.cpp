// Scene files: every kind of bad input gets one clear message naming the field.
#include "hemo/reference/sph.hpp"
#include "hemo/scene/builders.hpp"
#include "hemo/scene/scene.hpp"
#include "scene_errors.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include <fstream>
#include <nlohmann/json.hpp>

namespace hemo::scene {
namespace {

using Json = nlohmann::json;

Json validScene() {
  return Json::parse(R"({
    "scene": "t",
    "particles": { "spacing_m": 0.01 },
    "fluid": { "expected_max_speed_m_s": 1.0,
               "blocks": [ { "min_m": [0, 0, 0], "max_m": [0.1, 0.05, 0.2] } ] },
    "boundary": { "tanks": [ { "min_m": [0, 0, 0], "max_m": [0.3, 0.05, 0.3], "layers": 3 } ] },
    "domain": { "min_m": [-0.05, -0.05, -0.05], "max_m": [0.35, 0.1, 0.35] }
  })");
}


TEST(Scene, ValidSceneLoadsWithDefaultsAndDerivedSoundSpeed) {
  const Scene s = parseScene(validScene().dump(), "ok.json");
  EXPECT_EQ(s.name, "t");
  EXPECT_FLOAT_EQ(s.sph.spacing, 0.01f);
  EXPECT_FLOAT_EQ(s.sph.smoothingRatio, 1.3f);
  EXPECT_FLOAT_EQ(s.sph.soundSpeed, 10.0f);  // 10 x expected max speed
  EXPECT_FLOAT_EQ(s.sph.restDensity, 1000.0f);
  EXPECT_FLOAT_EQ(s.sph.gravity.z, -9.81f);
  ASSERT_EQ(s.blocks.size(), 1u);
  ASSERT_EQ(s.tanks.size(), 1u);
  EXPECT_TRUE(s.tanks[0].openTop);
}

// Periodic axes: accepted when the tank spans the domain there (no walls built across the
// axis); a period that is not a whole number of spacings, one thinner than 2.5 list radii,
// a tank that does not span the period, an unknown or repeated axis: each named.
TEST(Scene, PeriodicAxesAreCheckedAndDropTheWallsAcrossThem) {
  Json j = validScene();
  j["domain"]["min_m"][1] = 0.0;
  j["domain"]["max_m"][1] = 0.09;  // 9 spacings: at least three list radii (8.6 dp)
  j["boundary"]["tanks"][0]["max_m"][1] = 0.09;
  j["domain"]["periodic"] = Json::array({"y"});
  const Scene s = parseScene(j.dump(), "ok.json");
  EXPECT_TRUE(s.sph.periodic.y);
  EXPECT_FALSE(s.sph.periodic.x);
  EXPECT_TRUE(s.tanks[0].periodic.y);
  // 3 layers under the floor and beside the two x walls over the 9 y columns; open top.
  EXPECT_EQ(countParticles(s), std::uint64_t(36 * 9 * 33 - 30 * 9 * 30) + 10 * 5 * 20);
  const ParticleSet set = buildParticles(s);
  EXPECT_EQ(set.size(), countParticles(s));
  for (const auto& p : set.positions) EXPECT_TRUE(p.y > 0.0f && p.y < 0.09f) << "a particle outside the period";

  Json bad = j;
  bad["domain"]["max_m"][1] = 0.095;
  bad["boundary"]["tanks"][0]["max_m"][1] = 0.095;
  expectError(bad, {"domain.periodic", "whole number of spacings"});
  bad = j;
  bad["domain"]["max_m"][1] = 0.1;
  expectError(bad, {"boundary.tanks[0]", "span the domain", "periodic axis y"});
  bad = j;
  bad["domain"]["max_m"][1] = 0.12;
  bad["boundary"]["tanks"][0]["max_m"][1] = 0.12;
  bad["particles"]["spacing_m"] = 0.02;
  expectError(bad, {"domain.periodic", "at least 2.5 neighbour-list radii"});
  bad = j;
  bad["domain"]["periodic"] = Json::array({"w"});
  expectError(bad, {"domain.periodic[0]", "\"x\""});
  bad["domain"]["periodic"] = Json::array({"y", "y"});
  expectError(bad, {"domain.periodic", "twice"});
}

TEST(Scene, UnknownKeysAreNamed) {
  Json j = validScene();
  j["fluid"]["viscosty_pa_s"] = 0.1;
  expectError(j, {"fluid.viscosty_pa_s", "unknown key"});
  j = validScene();
  j["extra"] = 1;
  expectError(j, {"extra", "unknown key"});
}

TEST(Scene, WrongTypesAreNamed) {
  Json j = validScene();
  j["particles"]["spacing_m"] = "small";
  expectError(j, {"particles.spacing_m", "expected a number"});
  j = validScene();
  j["fluid"]["blocks"][0]["min_m"] = Json::array({0, 0});
  expectError(j, {"fluid.blocks[0].min_m", "3 numbers"});
  j = validScene();
  j["fluid"]["clamp_negative_pressure"] = 1;
  expectError(j, {"fluid.clamp_negative_pressure", "true or false"});
  j = validScene();
  j["time"] = Json::object({{"integrator", "euler"}});
  expectError(j, {"time.integrator", "symplectic_euler"});
  j = validScene();
  j["particles"]["neighbour_capacity"] = 64.5;
  expectError(j, {"particles.neighbour_capacity", "whole number"});
  j = validScene();
  j["fluid"]["density"] = "sum";
  expectError(j, {"fluid.density", "summation", "continuity"});
  j = validScene();
  j["fluid"]["density"] = "continuity";
  j["fluid"]["delta_sph"] = 2;
  expectError(j, {"fluid.delta_sph"});
  j = validScene();
  j["fluid"]["density"] = "continuity";
  EXPECT_EQ(parseScene(j.dump(), "ok.json").sph.densityMethod, sim::DensityMethod::Continuity);
}

// Values out of their range, and non-zero ones too small for single precision (a wall point's
// mass of 5e-324 kg passed the range check and reached the builder as 0), are named.
TEST(Scene, OutOfRangeValuesAreNamed) {
  Json j = validScene();
  j["particles"]["spacing_m"] = -0.01;
  expectError(j, {"particles.spacing_m", "must be in"});
  j = validScene();
  j["particles"]["spacing_m"] = 0;
  expectError(j, {"particles.spacing_m"});
  j = validScene();
  j["fluid"]["density_kg_m3"] = 1e9;
  expectError(j, {"fluid.density_kg_m3"});
  // in range as a double, but 0 (or denormal) in the engine's single precision
  j = validScene();
  j["fluid"]["viscosity_pa_s"] = 5e-324;
  expectError(j, {"fluid.viscosity_pa_s", "too small for single precision"});
  j["fluid"]["viscosity_pa_s"] = 1e-39;
  expectError(j, {"fluid.viscosity_pa_s", "too small for single precision"});
}

// The DFSPH solver's settings, and what it does not run, are named.
// particles.list_layout picks the neighbour list's layout (default: the device's choice).
TEST(Scene, ListLayoutIsParsedAndChecked) {
  EXPECT_EQ(parseScene(validScene().dump(), "ok.json").sph.listLayout, sim::ListLayout::Auto);
  const std::pair<const char*, sim::ListLayout> layouts[] = {{"auto", sim::ListLayout::Auto},
                                                             {"interleaved", sim::ListLayout::Interleaved},
                                                             {"contiguous", sim::ListLayout::Contiguous},
                                                             {"clusters", sim::ListLayout::Clusters}};
  for (const auto& [name, layout] : layouts) {
    Json j = validScene();
    j["particles"]["list_layout"] = name;
    EXPECT_EQ(parseScene(j.dump(), "ok.json").sph.listLayout, layout) << name;
  }
  Json j = validScene();
  j["particles"]["list_layout"] = "rows";
  expectError(j, {"particles.list_layout", "interleaved", "contiguous"});
}

TEST(Scene, PressureSolverSettingsAreCheckedAndItsLimitsNamed) {
  Json j = validScene();
  j["fluid"]["solver"] = "dfsph";
  j["fluid"]["solver_tolerance"] = 1e-4;
  j["fluid"]["solver_max_iterations"] = 40;
  const Scene s = parseScene(j.dump(), "ok.json");
  EXPECT_EQ(s.sph.pressureSolver, sim::PressureSolver::Dfsph);
  EXPECT_FLOAT_EQ(s.sph.solverTolerance, 1e-4f);
  EXPECT_EQ(s.sph.solverMaxIterations, 40u);
  EXPECT_TRUE(s.sph.solverCompressible);
  j["fluid"]["solver_compressible"] = false;
  EXPECT_FALSE(parseScene(j.dump(), "ok.json").sph.solverCompressible);
  j["fluid"]["solver_compressible"] = "yes";
  expectError(j, {"fluid.solver_compressible"});
  EXPECT_EQ(parseScene(validScene().dump(), "ok.json").sph.pressureSolver, sim::PressureSolver::Wcsph);
  j = validScene();
  j["fluid"]["solver"] = "iisph";
  expectError(j, {"fluid.solver", "wcsph", "dfsph"});
  j = validScene();
  j["fluid"]["solver_tolerance"] = 0;
  expectError(j, {"fluid.solver_tolerance"});
  j = validScene();
  j["fluid"]["solver_max_iterations"] = 0;
  expectError(j, {"fluid.solver_max_iterations"});
  j = validScene();
  j["fluid"]["solver"] = "dfsph";
  j["fluid"]["density"] = "continuity";
  expectError(j, {"fluid.solver", "summation"});
  j = validScene();
  j["fluid"]["solver"] = "dfsph";
  j["time"]["integrator"] = "rk2_midpoint";
  expectError(j, {"fluid.solver", "symplectic_euler"});
  j = validScene();
  j["fluid"]["solver"] = "dfsph";
  j["particles"]["neighbour_search"] = "cells";
  expectError(j, {"fluid.solver", "neighbour_search"});
  j = validScene();
  j["fluid"]["solver"] = "dfsph";
  j["particles"]["list_layout"] = "clusters";
  expectError(j, {"fluid.solver", "list_layout"});
  // a vessel with its inflow and lumen (background) pressure runs under DFSPH
  std::ifstream in(std::string(HEMO_SOURCE_DIR) + "/scenes/aneurysm.json");
  Json v = Json::parse(in);
  v["fluid"]["solver"] = "dfsph";
  const Scene vessel = parseScene(v.dump(), "aneurysm.json");
  EXPECT_EQ(vessel.sph.pressureSolver, sim::PressureSolver::Dfsph);
  EXPECT_GT(vessel.sph.backgroundPressure, 0.0f);
  ASSERT_TRUE(vessel.vessel.has_value());
}

TEST(Scene, RheologyIsParsedAndChecked) {
  EXPECT_EQ(parseScene(validScene().dump(), "ok.json").sph.rheology, sim::Rheology::Newtonian);
  Json j = validScene();
  j["fluid"]["rheology"] = {{"model", "carreau_yasuda"}};
  Scene s = parseScene(j.dump(), "ok.json");
  EXPECT_EQ(s.sph.rheology, sim::Rheology::CarreauYasuda);
  EXPECT_TRUE(s.sph.nonNewtonian());
  // the defaults: Cho & Kensey's whole blood
  EXPECT_FLOAT_EQ(s.sph.carreau.mu0, 0.056f);
  EXPECT_FLOAT_EQ(s.sph.carreau.muInf, 0.00345f);
  EXPECT_FLOAT_EQ(s.sph.carreau.lambda, 3.313f);
  EXPECT_FLOAT_EQ(s.sph.carreau.n, 0.3568f);
  EXPECT_FLOAT_EQ(s.sph.carreau.a, 2.0f);
  EXPECT_DOUBLE_EQ(s.sph.maxViscosity(), double(0.056f));
  // the law: mu_0 at rest, mu_inf at high shear, the power law between
  EXPECT_NEAR(s.sph.carreau.at(0.0), 0.056, 1e-8);
  EXPECT_NEAR(s.sph.carreau.at(1e9), 0.00345, 1e-6);
  const double g = 100.0, lg = 3.313 * g;
  EXPECT_NEAR(s.sph.carreau.at(g), 0.00345 + (0.056 - 0.00345) * std::pow(1.0 + lg * lg, (0.3568 - 1.0) / 2.0), 1e-7);
  j["fluid"]["rheology"] = {{"model", "carreau_yasuda"}, {"zero_shear_viscosity_pa_s", 0.2}, {"infinite_shear_viscosity_pa_s", 0.05},
                            {"relaxation_time_s", 0.05}, {"power_index", 0.3}, {"yasuda_exponent", 1.5}};
  s = parseScene(j.dump(), "ok.json");
  EXPECT_FLOAT_EQ(s.sph.carreau.mu0, 0.2f);
  EXPECT_FLOAT_EQ(s.sph.carreau.muInf, 0.05f);
  EXPECT_FLOAT_EQ(s.sph.carreau.lambda, 0.05f);
  EXPECT_FLOAT_EQ(s.sph.carreau.n, 0.3f);
  EXPECT_FLOAT_EQ(s.sph.carreau.a, 1.5f);
  // the viscous time-step limit follows the largest viscosity, mu_0
  const sim::SphParams p = sim::makeParams(s.sph);
  EXPECT_NEAR(p.dtViscous, 0.125 * s.sph.h() * s.sph.h() * s.sph.restDensity / 0.2, 1e-6 * p.dtViscous);
  EXPECT_GT(p.carreau[2], 0.0f);
  EXPECT_EQ(sim::makeParams(parseScene(validScene().dump(), "ok.json").sph).carreau[2], 0.0f);

  auto bad = [&](const Json& rheology, std::initializer_list<const char*> words) {
    Json k = validScene();
    k["fluid"]["rheology"] = rheology;
    expectError(k, words);
  };
  bad({{"model", "casson"}}, {"fluid.rheology.model", "newtonian", "carreau_yasuda"});
  bad({{"model", "carreau_yasuda"}, {"zero_shear_viscosity_pa_s", 0.01}, {"infinite_shear_viscosity_pa_s", 0.02}},
      {"fluid.rheology.infinite_shear_viscosity_pa_s", "zero_shear_viscosity_pa_s"});
  bad({{"model", "carreau_yasuda"}, {"power_index", 1.5}}, {"fluid.rheology.power_index"});
  bad({{"model", "carreau_yasuda"}, {"relaxation_time_s", 0}}, {"fluid.rheology.relaxation_time_s"});
  bad({{"model", "carreau_yasuda"}, {"yasuda_exponent", -1}}, {"fluid.rheology.yasuda_exponent"});
  bad({{"power_index", 0.5}}, {"fluid.rheology.power_index", "carreau_yasuda"});
  Json k = validScene();
  k["fluid"]["rheology"] = {{"model", "carreau_yasuda"}};
  k["fluid"]["viscosity_pa_s"] = 0.0035;
  expectError(k, {"fluid.viscosity_pa_s", "carreau_yasuda"});
}

TEST(Scene, BoxesWithMinAboveMaxAreNamed) {
  Json j = validScene();
  j["fluid"]["blocks"][0]["min_m"] = Json::array({0.2, 0, 0});
  expectError(j, {"fluid.blocks[0]", "min_m must be below max_m", "axis x"});
  j = validScene();
  j["domain"]["max_m"][2] = -1.0;
  expectError(j, {"domain", "axis z"});
}

TEST(Scene, NonFiniteNumbersAndBadJsonAreRejected) {
  // JSON has no NaN literal; a NaN can only arrive as bad JSON or an overflowing number.
  std::string text = validScene().dump();
  text.replace(text.find("0.01"), 4, "NaN");
  EXPECT_THROW(parseScene(text, "bad.json"), SceneError);
  std::string big = validScene().dump();
  big.replace(big.find("0.01"), 4, "1e999");
  EXPECT_THROW(parseScene(big, "bad.json"), SceneError);
  try {
    parseScene("{ \"scene\": ", "broken.json");
    FAIL();
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("not valid JSON"), std::string::npos) << e.what();
  }
}

TEST(Scene, MissingRequiredFieldsAreNamed) {
  Json j = validScene();
  j["particles"].erase("spacing_m");
  expectError(j, {"particles.spacing_m", "required"});
  j = validScene();
  j.erase("domain");
  expectError(j, {"domain", "required"});
  j = validScene();
  j["fluid"]["blocks"] = Json::array();
  expectError(j, {"fluid.blocks", "at least 1", "vessel"});
}

TEST(Scene, GeometryOutsideTheDomainIsNamed) {
  Json j = validScene();
  j["fluid"]["blocks"][0]["max_m"][0] = 1.0;
  expectError(j, {"fluid.blocks[0]", "outside the domain"});
  j = validScene();
  j["boundary"]["tanks"][0]["min_m"][1] = -0.04;  // its 3 layers reach y = -0.07
  expectError(j, {"boundary.tanks[0]", "layers"});
}

TEST(Scene, MissingFileIsAClearError) {
  try {
    loadScene("/nonexistent/dir/scene.json");
    FAIL();
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/scene.json"), std::string::npos);
  }
}

TEST(Scene, ShippedScenesLoad) {
  int scenes = 0;
  for (const auto& entry : std::filesystem::directory_iterator(std::string(HEMO_SOURCE_DIR) + "/scenes")) {
    if (entry.path().extension() != ".json") continue;
    const Scene s = loadScene(entry.path());
    EXPECT_TRUE(!s.blocks.empty() || s.vessel) << entry.path();
    ++scenes;
  }
  EXPECT_GE(scenes, 7);
}

// Tools: a probe with a keyframed path loads (orientation normalised, contact distance dp by
// default), and a blade with its cutting keys; keyframes out of order, an unknown kind, a tip
// outside the domain, a non-positive radius, a zero or non-4 orientation, a turn of 90 degrees
// between keys, a tip faster than sound, a probe's key that cuts, a blade without an edge, a
// grip on a tool that is not a grasper, a negative grip stiffness, a duplicate name and more
// than 8 tools each get an error naming the field.
TEST(Scene, ToolsAreParsedAndBadOnesNamed) {
  Json j = validScene();
  j["tools"] = Json::parse(R"([{ "name": "probe", "radius_m": 0.003, "length_m": 0.02,
      "path": [ { "time_s": 0, "position_m": [0.05, 0.02, 0.25] },
                { "time_s": 0.5, "position_m": [0.05, 0.02, 0.15], "orientation_wxyz": [2, 0, 0, 0] } ] }])");
  const Scene s = parseScene(j.dump(), "ok.json");
  ASSERT_EQ(s.tools.size(), 1u);
  EXPECT_EQ(s.tools[0].name, "probe");
  EXPECT_FLOAT_EQ(s.tools[0].contactDistance, 0.01f);
  ASSERT_EQ(s.tools[0].keys.size(), 2u);
  EXPECT_FLOAT_EQ(s.tools[0].keys[1].orientation.w, 1.0f);
  EXPECT_FLOAT_EQ(s.tools[0].keys[1].position.z, 0.15f);

  auto with = [&](const char* path, const Json& value) {
    Json k = j;
    k["tools"][0] = Json(j["tools"][0]).patch(Json::array({{{"op", "replace"}, {"path", path}, {"value", value}}}));
    return k;
  };
  auto added = [&](const char* path, const Json& value) {
    Json k = j;
    k["tools"][0] = Json(j["tools"][0]).patch(Json::array({{{"op", "add"}, {"path", path}, {"value", value}}}));
    return k;
  };
  expectError(with("/path/1/time_s", 0.0), {"tools[0].path[1].time_s", "time order"});
  expectError(added("/kind", "scalpel"), {"tools[0].kind", "scalpel", "probe"});
  expectError(with("/path/0/position_m", Json::array({0.05, 0.02, 2.0})), {"tools[0].path[0].position_m", "outside the domain"});
  expectError(with("/radius_m", 0.0), {"tools[0].radius_m"});
  expectError(with("/radius_m", -0.001), {"tools[0].radius_m"});
  expectError(added("/path/0/orientation_wxyz", Json::array({0, 0, 0, 0})), {"tools[0].path[0].orientation_wxyz", "zero"});
  expectError(added("/path/0/orientation_wxyz", Json::array({1, 0, 0})), {"tools[0].path[0].orientation_wxyz", "4 numbers"});
  expectError(added("/path/0/orientation_wxyz", Json::array({0, 1, 0, 0})), {"tools[0]", "90 degrees"});
  expectError(with("/path/1/time_s", 1e-3), {"tools[0].path[1].position_m", "faster than the speed of sound"});
  expectError(with("/path", Json::array()), {"tools[0].path", "at least 1"});
  expectError(added("/contact_distance_m", 0.5), {"tools[0].contact_distance_m", "kernel support"});
  expectError(added("/path/0/cutting", true), {"tools[0].path[0].cutting", "only a blade cuts"});
  expectError(added("/path/0/jaw_opening_m", 0.002), {"tools[0].path[0].jaw_opening_m", "only a grasper"});
  {
    Json k = j;
    k["tools"][0]["kind"] = "grasper";
    k["tools"][0]["path"][0]["jaw_opening_m"] = -0.001;
    expectError(k, {"tools[0].path[0].jaw_opening_m", "[0, 1000]"});
    k["tools"][0]["path"][0]["jaw_opening_m"] = 0.004;
    const Scene g = parseScene(k.dump(), "ok.json");
    EXPECT_EQ(g.tools[0].kind, sim::ToolKind::Grasper);
    EXPECT_FLOAT_EQ(g.tools[0].keys[0].jawOpening, 0.004f);
    EXPECT_EQ(g.tools[0].gripStiffness, 0.0f) << "no vessel: nothing to grip, no default stiffness";
    k["tools"][0]["grip_stiffness_N_m"] = 20.0;
    EXPECT_FLOAT_EQ(parseScene(k.dump(), "ok.json").tools[0].gripStiffness, 20.0f);
    k["tools"][0]["grip"] = false;
    EXPECT_EQ(parseScene(k.dump(), "ok.json").tools[0].gripStiffness, 0.0f);
    k["tools"][0]["grip_stiffness_N_m"] = -1.0;
    expectError(k, {"tools[0].grip_stiffness_N_m"});
  }
  expectError(added("/grip", true), {"tools[0].grip", "only a grasper grips"});
  expectError(added("/grip_stiffness_N_m", 5.0), {"tools[0].grip_stiffness_N_m", "only a grasper grips"});
  EXPECT_EQ(parseScene(added("/grip", false).dump(), "ok.json").tools[0].gripStiffness, 0.0f);
  {
    Json k = j;
    k["tools"][0]["kind"] = "blade";
    k["tools"][0]["length_m"] = 0.0;
    expectError(k, {"tools[0].length_m", "a blade needs an edge"});
    k["tools"][0]["length_m"] = 0.01;
    k["tools"][0]["path"][0]["cutting"] = true;
    const Scene b = parseScene(k.dump(), "ok.json");
    EXPECT_EQ(b.tools[0].kind, sim::ToolKind::Blade);
    EXPECT_TRUE(b.tools[0].keys[0].cutting);
    EXPECT_FALSE(b.tools[0].keys[1].cutting);
  }
  {
    Json k = j;
    k["tools"].push_back(j["tools"][0]);
    expectError(k, {"tools[1].name", "another tool"});
  }
  {
    Json k = j;
    for (int t = 1; t < 9; ++t) {
      k["tools"].push_back(j["tools"][0]);
      k["tools"][t]["name"] = "probe" + std::to_string(t);
    }
    expectError(k, {"tools", "at most 8"});
  }
}

TEST(Scene, SchemaDocsAreUpToDate) {
  std::ifstream in(std::string(HEMO_SOURCE_DIR) + "/docs/scene-format.md");
  ASSERT_TRUE(in) << "docs/scene-format.md is missing";
  const std::string doc((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(doc.find(schemaMarkdown()), std::string::npos)
      << "docs/scene-format.md does not contain the current parameter table; regenerate it with "
         "`hemo-run --describe-scene`";
}

TEST(Builders, TankAndBlockCountsMatchTheEstimate) {
  const Scene s = parseScene(validScene().dump(), "ok.json");
  const ParticleSet set = buildParticles(s);
  EXPECT_EQ(set.size(), countParticles(s));
  EXPECT_EQ(set.fluid, 10u * 5u * 20u);
  // open top: (30+6)(5+6)(30+3) - 30*5*30
  EXPECT_EQ(set.boundary, 36u * 11u * 33u - 30u * 5u * 30u);
  for (std::uint32_t i = set.fluid; i < set.size(); ++i) {
    const glm::vec3 n(set.normals[i]);
    EXPECT_NEAR(glm::length(n), 1.0f, 1e-5f);
  }
}

// A body-centred block: two particles per cell of edge ~2^(1/3) dp, the cells stretched to a
// whole number per axis (0.1 / 0.0126 -> 8 cells of 12.5 mm along x and z; 0.06 -> 5 of 12 mm
// along y), every particle inside the box, a quarter cell from its faces; the kernel sum at
// a particle whose support lies inside the block gives the rest density exactly (the mass is
// calibrated on this lattice); the particles per volume are 1 / dp^3 times the stretch (here
// 1.0667: the y cells are 4.8% short of 12.6 mm).
TEST(Builders, BodyCentredBlockFillsTheBoxAtTheRestDensity) {
  Json j = validScene();
  j["fluid"]["blocks"][0]["max_m"] = Json::array({0.1, 0.06, 0.1});
  j["fluid"]["blocks"][0]["lattice"] = "bcc";
  const Scene s = parseScene(j.dump(), "ok.json");
  ASSERT_EQ(s.blocks[0].lattice, FluidBlock::Lattice::BodyCentred);
  const ParticleSet set = buildParticles(s);
  EXPECT_EQ(set.size(), countParticles(s));
  ASSERT_EQ(set.fluid, 2u * 8u * 5u * 8u);
  const glm::vec3 box(0.1f, 0.06f, 0.1f), edge(0.0125f, 0.012f, 0.0125f);
  double nearest = 1e9;
  std::uint32_t centre = 0;
  for (std::uint32_t i = 0; i < set.fluid; ++i) {
    const glm::vec3 p(set.positions[i]);
    for (int a = 0; a < 3; ++a) {
      EXPECT_GE(p[a], 0.25f * edge[a] - 1e-6f) << "particle " << i << " axis " << a;
      EXPECT_LE(p[a], box[a] - 0.25f * edge[a] + 1e-6f) << "particle " << i << " axis " << a;
    }
    if (glm::length(p - 0.5f * box) < glm::length(glm::vec3(set.positions[centre]) - 0.5f * box)) centre = i;
  }
  const glm::dvec3 c(glm::vec3(set.positions[centre]));
  double rho = 0.0;
  for (std::uint32_t j2 = 0; j2 < set.fluid; ++j2) {
    const double r = glm::length(glm::dvec3(glm::vec3(set.positions[j2])) - c);
    if (j2 != centre) nearest = std::min(nearest, r);
    rho += double(set.positions[j2].w) * reference::kernelW(r, s.sph.h());
  }
  for (int a = 0; a < 3; ++a) {
    ASSERT_TRUE(c[a] - 2.0 * s.sph.h() > 0.0 && c[a] + 2.0 * s.sph.h() < box[a]) << "the support must lie inside";
  }
  EXPECT_NEAR(rho, s.sph.restDensity, 1e-4 * s.sph.restDensity);
  // nearest neighbour: half the cell diagonal
  EXPECT_NEAR(nearest, 0.5 * glm::length(glm::dvec3(edge)), 1e-6);
  const double perVolume = set.fluid / double(box.x * box.y * box.z), cubic = 1.0 / std::pow(double(s.sph.spacing), 3.0);
  EXPECT_NEAR(perVolume / cubic, 2.0 / (edge.x * edge.y * edge.z) / cubic, 1e-4);
  EXPECT_NEAR(perVolume / cubic, 1.0667, 1e-3);
  // A cubic block of the same box keeps the dp lattice and the calibrated mass.
  j["fluid"]["blocks"][0]["lattice"] = "cubic";
  const ParticleSet cubicSet = buildParticles(parseScene(j.dump(), "ok.json"));
  EXPECT_EQ(cubicSet.fluid, 10u * 6u * 10u);
  EXPECT_FLOAT_EQ(cubicSet.positions[0].w, s.sph.particleMass());
  j["fluid"]["blocks"][0]["lattice"] = "fcc";
  expectError(j, {"fluid.blocks[0].lattice", "bcc"});
}

}  // namespace
}  // namespace hemo::scene
