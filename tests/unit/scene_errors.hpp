#pragma once
// Shared by the scene-file tests: a bad scene must be rejected with one SceneError naming the
// file and containing every expected fragment (field names, the problem).
#include "hemo/scene/scene.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <initializer_list>
#include <string>

namespace hemo::scene {

inline void expectError(const nlohmann::json& j, std::initializer_list<const char*> fragments) {
  try {
    parseScene(j.dump(), "bad.json");
    FAIL() << "accepted: " << j.dump();
  } catch (const SceneError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("bad.json"), std::string::npos) << m;
    for (const char* f : fragments) EXPECT_NE(m.find(f), std::string::npos) << "'" << f << "' not in: " << m;
  }
}

}  // namespace hemo::scene
