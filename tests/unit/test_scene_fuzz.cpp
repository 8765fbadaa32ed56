// A seeded mutation test of the scene loader: thousands of scenes made from the shipped ones
// by random edits, as a hand-edited or corrupted file would be, must each load or be refused
// with a SceneError (never another exception, a crash or a hang); those that load and are
// small enough are built (particles, wall, springs) the same way. Under the asan preset
// (AddressSanitizer and UndefinedBehaviorSanitizer) every mutant also runs without a memory or
// undefined-behaviour error. The seed is fixed, so a failure names a mutant that reproduces.
#include "hemo/scene/build.hpp"
#include "hemo/scene/scene.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace hemo::test {
namespace {

using Json = nlohmann::json;

std::string readFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Every value in the document, as a JSON pointer.
void collectPointers(const Json& j, const Json::json_pointer& at, std::vector<Json::json_pointer>& out) {
  out.push_back(at);
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it) collectPointers(it.value(), at / it.key(), out);
  } else if (j.is_array()) {
    for (std::size_t k = 0; k < j.size(); ++k) collectPointers(j[k], at / k, out);
  }
}

// A value of any type, biased to the edges a loader must check.
Json randomValue(std::mt19937& rng, const Json& old) {
  const double numbers[] = {0.0, -1.0, 1.0, 1e-30, 1e30, -1e30, 3.0, 0.5, 1e6, 1e-6, 2.5, -0.0,
                            std::numeric_limits<double>::max(), std::numeric_limits<double>::denorm_min()};
  switch (std::uniform_int_distribution<int>(0, 11)(rng)) {
    case 0: return numbers[std::uniform_int_distribution<std::size_t>(0, std::size(numbers) - 1)(rng)];
    case 1: return old.is_number() ? Json(old.get<double>() * std::uniform_real_distribution<double>(-3.0, 3.0)(rng)) : Json(7);
    case 2: return std::uniform_int_distribution<std::int64_t>(-5, 5000000000ll)(rng);
    case 3: return Json("");
    case 4: return Json("tube");
    case 5: return Json(nullptr);
    case 6: return Json(true);
    case 7: return Json::array();
    case 8: return Json::array({1.0, 2.0});
    case 9: return Json::array({0.0, 0.0, 0.0, 0.0});
    case 10: return Json::object();
    default: return old.is_array() && !old.empty() ? Json::array({old[0], old[0], old[0]}) : Json(-2);
  }
}

// One structural edit: a value replaced, a key removed, an unknown key added, an array
// element dropped or doubled.
void mutate(Json& doc, std::mt19937& rng) {
  std::vector<Json::json_pointer> pointers;
  collectPointers(doc, Json::json_pointer(), pointers);
  const Json::json_pointer at = pointers[std::uniform_int_distribution<std::size_t>(0, pointers.size() - 1)(rng)];
  const int kind = std::uniform_int_distribution<int>(0, 4)(rng);
  if (at.empty()) {
    doc[std::string("unknown_") + char('a' + rng() % 26)] = 1;
    return;
  }
  const Json::json_pointer parent = at.parent_pointer();
  Json& container = doc[parent];
  const std::string key = at.back();
  if (kind == 0 && container.is_object()) {
    container.erase(key);
  } else if (kind == 1 && container.is_object()) {
    container[key + "_x"] = randomValue(rng, Json());
  } else if (kind == 2 && container.is_array()) {
    const std::size_t k = std::stoul(key);
    if (rng() % 2) {
      container.erase(k);
    } else {
      container.push_back(container[k]);
    }
  } else {
    doc[at] = randomValue(rng, doc[at]);
  }
}

// A byte-level edit of the text: a byte changed, a run deleted, or the file cut short.
std::string corruptText(std::string text, std::mt19937& rng) {
  if (text.empty()) return text;
  const std::size_t at = std::uniform_int_distribution<std::size_t>(0, text.size() - 1)(rng);
  switch (rng() % 3) {
    case 0: text[at] = static_cast<char>(rng() % 256); break;
    case 1: text.erase(at, std::min<std::size_t>(1 + rng() % 16, text.size() - at)); break;
    default: text.resize(at); break;
  }
  return text;
}

TEST(SceneFuzz, MutatedScenesLoadOrAreRefusedWithASceneError) {
  const std::filesystem::path dir = std::filesystem::path(HEMO_SOURCE_DIR) / "scenes";
  std::vector<std::string> texts;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() == ".json") texts.push_back(readFile(entry.path()));
  }
  std::sort(texts.begin(), texts.end());
  ASSERT_GE(texts.size(), 5u);
  std::mt19937 rng(20261128u);
  // HEMO_FUZZ_MUTANTS sets a shorter budget (the sanitizer run in `make test`).
  const int kMutants = std::getenv("HEMO_FUZZ_MUTANTS") ? std::max(50, std::atoi(std::getenv("HEMO_FUZZ_MUTANTS"))) : 3000;
  // Scenes small enough to build here (a mutant may ask for billions of particles, which is
  // the simulation's fit check's business: hemo-run refuses it before building). A vessel from
  // a mesh (its file found beside the scenes, as hemo-run finds it) takes 0.05 s to load and
  // check and seconds to count and build (the layout of its wall is the build): each mesh
  // scene takes every fourth of its turns, and the first loaded mesh mutant is built, with
  // the full budget only (the sanitizer run's unit tests build mesh vessels already).
  constexpr std::uint64_t kBuildLimit = 60000;
  const int meshBuilds = std::getenv("HEMO_FUZZ_MUTANTS") ? 0 : 1;
  std::vector<bool> meshScene;
  for (const std::string& t : texts) meshScene.push_back(Json::parse(t).value("vessel", Json::object()).value("shape", "") == "mesh");
  ASSERT_GE(std::count(meshScene.begin(), meshScene.end(), true), 1) << "the scenes hold a mesh scene";
  int loaded = 0, refused = 0, built = 0, meshLoaded = 0;
  for (int m = 0; m < kMutants; ++m) {
    const std::size_t which = static_cast<std::size_t>(m) % texts.size();
    if (meshScene[which] && (m / texts.size()) % 4 != 0) continue;
    const std::string& base = texts[which];
    std::string text;
    if (m % 4 == 3) {
      text = corruptText(base, rng);
    } else {
      Json doc = Json::parse(base);
      const int edits = 1 + static_cast<int>(rng() % 3);
      for (int e = 0; e < edits; ++e) mutate(doc, rng);
      text = doc.dump();
    }
    SCOPED_TRACE(testing::Message() << "mutant " << m << ": " << text.substr(0, 2000));
    try {
      const scene::Scene scene = scene::parseScene(text, "mutant.json", dir);
      ++loaded;
      const bool meshed = scene.vessel && scene.vessel->shape == scene::Vessel::Shape::Mesh;
      meshLoaded += meshed;
      if (meshed && meshLoaded > meshBuilds) continue;
      const std::uint64_t count = scene::countSceneParticles(scene);
      if (count <= kBuildLimit) {
        const scene::SceneBuild build = scene::buildScene(scene);
        EXPECT_EQ(build.particles.positions.size(), count);
        ++built;
      }
    } catch (const scene::SceneError& e) {
      ++refused;
      EXPECT_NE(std::string(e.what()).find("mutant.json"), std::string::npos) << e.what();
    } catch (const std::exception& e) {
      ADD_FAILURE() << "not a SceneError: " << e.what();
    }
  }
  std::printf("scene fuzz: %d mutants, %d loaded (%d built, %d with a mesh vessel), %d refused\n", kMutants, loaded, built,
              meshLoaded, refused);
  EXPECT_GT(meshLoaded, 0) << "mutants of the mesh scene must load too (its mesh found beside it)";
  EXPECT_GT(loaded, kMutants / 20) << "the mutations must leave some scenes valid";
  EXPECT_GT(refused, kMutants / 2);
}

}  // namespace
}  // namespace hemo::test
